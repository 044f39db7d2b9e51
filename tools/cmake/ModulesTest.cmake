# ctest "install: -DHAPTO_MODULES=index configures with no USB, HTTP or mesh library".
# Run as: cmake -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -P ModulesTest.cmake
# Configures hapto's sources for the index alone where pkg-config finds nothing (no libusb-1.0,
# no cpp-httplib) and meshoptimizer and Eigen are disabled, and checks that the build
# holds the index and what it needs and nothing above it (built or installed); then that the same
# environment does hide the view's needs (configuring for the view fails, naming one).
# Configures only: nothing is built.
cmake_minimum_required(VERSION 3.25)
foreach(var SOURCE_DIR WORK_DIR GENERATOR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "ModulesTest.cmake: pass -D${var}=...")
  endif()
endforeach()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR}/no-pkgconfig)
set(hidden ${CMAKE_COMMAND} -E env PKG_CONFIG_LIBDIR=${WORK_DIR}/no-pkgconfig
    --unset=PKG_CONFIG_PATH)
set(args -G ${GENERATOR} --no-warn-unused-cli -DCMAKE_DISABLE_FIND_PACKAGE_meshoptimizer=ON
    -DCMAKE_DISABLE_FIND_PACKAGE_Eigen3=ON)

execute_process(COMMAND ${hidden} ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/index
                        ${args} -DHAPTO_MODULES=index
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring with -DHAPTO_MODULES=index failed (${rc}):\n${out}")
endif()
file(READ ${WORK_DIR}/index/build.ninja ninja)
foreach(module core io scenes index)
  if(NOT ninja MATCHES "libhapto_${module}\\.a")
    message(FATAL_ERROR "-DHAPTO_MODULES=index does not build hapto_${module}")
  endif()
endforeach()
foreach(module devices runtime experiments view)
  if(ninja MATCHES "libhapto_${module}\\.a")
    message(FATAL_ERROR "-DHAPTO_MODULES=index builds hapto_${module} too")
  endif()
endforeach()
# Its install holds those libraries' package and nothing that needs the others (the example,
# the Falcon's udev rule, the hapto command).
file(READ ${WORK_DIR}/index/cmake_install.cmake install_rules)
if(NOT install_rules MATCHES "haptoTargets-index\\.cmake"
   OR install_rules MATCHES "haptoTargets-devices")
  message(FATAL_ERROR "-DHAPTO_MODULES=index does not install exactly core, io, scenes and index")
endif()
foreach(needs_more "99-hapto-falcon\\.rules" "hapto/examples" "/bin/hapto")
  if(install_rules MATCHES "${needs_more}")
    message(FATAL_ERROR "-DHAPTO_MODULES=index installs ${needs_more}, which needs other modules")
  endif()
endforeach()

# (Eigen, a build-time need of the Falcon's kinematics, is left findable here, so that what
# stops the configuration is a hidden library.)
execute_process(COMMAND ${hidden} ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/view
                        -G ${GENERATOR} --no-warn-unused-cli
                        -DCMAKE_DISABLE_FIND_PACKAGE_meshoptimizer=ON -DHAPTO_MODULES=view
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(rc EQUAL 0 OR NOT out MATCHES "libusb-1.0|cpp-httplib|meshoptimizer")
  message(FATAL_ERROR "configuring with -DHAPTO_MODULES=view where libusb-1.0, cpp-httplib "
                      "and meshoptimizer are hidden should fail naming one (${rc}):\n${out}")
endif()
message(STATUS "-DHAPTO_MODULES=index configured with no USB, HTTP or mesh library")
