# ctest "install: README's two_hands snippet and pkg-config line build against an installed hapto".
# Run as: cmake -DBINARY_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX=...
#         [-DLAUNCHER=...] [-DCXX_FLAGS=...] [-DLINKER_FLAGS=...] -P InstallTest.cmake
# Installs the build into WORK_DIR/prefix and checks what an application gets there: the
# installed copy of the two_hands example (share/hapto/examples) builds with find_package(hapto)
# (no CMAKE_CXX_STANDARD: C++20 must come from the exported targets) and README shows its
# CMakeLists.txt exactly; find_package(hapto COMPONENTS index) works where pkg-config finds
# nothing and the view's and the Falcon's packages are disabled (tools/cmake/consumers/index),
# and the view's component asked for there fails naming what it needs (optional, it is absent:
# tools/cmake/consumers/optional); an application serving the installed view answers the page
# and three.js (tools/cmake/consumers/view); hapto-index.pc links the index program with nothing
# of USB, HTTP or meshes and hapto-view.pc the view's; README's pkg-config line builds
# tools/cmake/PkgConfigApp.cpp and it runs; the udev rule, the licence and hapto/Version.h are
# installed.
cmake_minimum_required(VERSION 3.25)
foreach(var BINARY_DIR SOURCE_DIR WORK_DIR GENERATOR CXX)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "InstallTest.cmake: pass -D${var}=...")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    list(JOIN ARGN " " command)
    message(FATAL_ERROR "failed (${rc}): ${command}\n${out}")
  endif()
endfunction()

# 1. The README shows the example's CMakeLists.txt, byte for byte.
set(example ${SOURCE_DIR}/tools/examples/two_hands)
file(READ ${example}/CMakeLists.txt listfile)
file(READ ${SOURCE_DIR}/README.md readme)
string(FIND "${readme}" "```cmake\n${listfile}```" at)
if(at EQUAL -1)
  message(FATAL_ERROR "README.md does not show tools/examples/two_hands/CMakeLists.txt exactly "
                      "in a ```cmake block; copy the file into README's library section")
endif()

# 2. Install into a fresh prefix.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${prefix})
set(installed_example ${prefix}/share/hapto/examples/two_hands)
foreach(f include/hapto/Version.h include/hapto/runtime/Runtime.h include/hapto/view/ViewServer.h
          lib/udev/rules.d/99-hapto-falcon.rules share/licenses/hapto/LICENSE bin/hapto
          share/hapto/examples/two_hands/CMakeLists.txt share/hapto/examples/two_hands/main.cpp)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
file(GLOB pc ${prefix}/lib*/pkgconfig/hapto.pc ${prefix}/lib/*/pkgconfig/hapto.pc)
if(NOT pc)
  message(FATAL_ERROR "not installed: hapto.pc")
endif()
file(GLOB_RECURSE exported ${prefix}/*/haptoTargets-*.cmake)
foreach(file ${exported})
  file(READ "${file}" targets)
  foreach(internal hapto_warnings hapto_catch_main)
    if(targets MATCHES "${internal}")
      message(FATAL_ERROR "the exported targets (${file}) name the build helper ${internal}")
    endif()
  endforeach()
endforeach()

# 3. Applications against the installed hapto: configure (in an environment), build, run.
set(configure_args -G ${GENERATOR} -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${prefix}
    -DCMAKE_BUILD_TYPE=Release --no-warn-unused-cli)
if(LAUNCHER)
  list(APPEND configure_args -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
# The installed libraries carry the build's flags (a sanitizer preset's instrumentation): the
# application must be built and linked with them too.
if(CXX_FLAGS)
  list(APPEND configure_args "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}")
endif()
if(LINKER_FLAGS)
  list(APPEND configure_args "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
endif()
# No package a consumer of the index alone may need: pkg-config searches an empty folder (no
# libusb-1.0, no cpp-httplib) and the other packages of the Falcon and the view are disabled.
file(MAKE_DIRECTORY ${WORK_DIR}/no-pkgconfig)
set(without_device_and_view_packages ${CMAKE_COMMAND} -E env
    PKG_CONFIG_LIBDIR=${WORK_DIR}/no-pkgconfig --unset=PKG_CONFIG_PATH)
set(disabled_packages -DCMAKE_DISABLE_FIND_PACKAGE_meshoptimizer=ON
    -DCMAKE_DISABLE_FIND_PACKAGE_Eigen3=ON)
# consumer(<name> <source> [ENV <command prefix>...] [ARGS <configure args>...]): builds it in
# WORK_DIR/<name>.
function(consumer name source)
  cmake_parse_arguments(C "" "" "ENV;ARGS" ${ARGN})
  run(${C_ENV} ${CMAKE_COMMAND} -S ${source} -B ${WORK_DIR}/${name} ${configure_args} ${C_ARGS})
  run(${CMAKE_COMMAND} --build ${WORK_DIR}/${name})
  message(STATUS "${name} built against ${prefix}")
endfunction()

consumer(two_hands ${installed_example})
consumer(index ${SOURCE_DIR}/tools/cmake/consumers/index ENV ${without_device_and_view_packages}
         ARGS ${disabled_packages})
run(${WORK_DIR}/index/index_consumer)
# The same environment does hide the view's needs: asking for the view fails, naming them.
execute_process(COMMAND ${without_device_and_view_packages} ${CMAKE_COMMAND}
                        -S ${SOURCE_DIR}/tools/cmake/consumers/view -B ${WORK_DIR}/view-hidden
                        ${configure_args} ${disabled_packages}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(rc EQUAL 0 OR NOT out MATCHES "libusb-1.0|cpp-httplib|meshoptimizer")
  message(FATAL_ERROR "find_package(hapto COMPONENTS view) without libusb-1.0, cpp-httplib "
                      "and meshoptimizer should fail naming one (${rc}):\n${out}")
endif()
# There, a component whose packages are missing (or an unknown one) is absent when optional,
# and asked for as required it fails naming the reason (tools/cmake/consumers/optional).
run(${without_device_and_view_packages} ${CMAKE_COMMAND}
    -S ${SOURCE_DIR}/tools/cmake/consumers/optional -B ${WORK_DIR}/optional ${configure_args}
    ${disabled_packages})
consumer(view ${SOURCE_DIR}/tools/cmake/consumers/view)
run(${WORK_DIR}/view/view_consumer)

# 4. README's pkg-config line builds and links a program against the installed hapto (static
#    libraries: the .pc file must bring every dependency), and the program runs. The line is
#    taken from README as it is; only its leading `c++` becomes this build's compiler and flags.
find_program(PKG_CONFIG pkg-config REQUIRED)
string(REGEX MATCHALL "\n(c\\+\\+ [^\n]*\\$\\(pkg-config [^\n]*)" lines "${readme}")
list(LENGTH lines count)
if(NOT count EQUAL 1)
  message(FATAL_ERROR "README.md should show one line `c++ ... $(pkg-config ...) ...` building "
                      "a program against hapto; found ${count}")
endif()
string(STRIP "${lines}" line)
string(REGEX REPLACE "^c\\+\\+ " "" rest "${line}")
list(GET pc 0 pcfile)
get_filename_component(pcdir ${pcfile} DIRECTORY)
set(ENV{PKG_CONFIG_PATH} ${pcdir})
set(app ${WORK_DIR}/pkg-config)
file(MAKE_DIRECTORY ${app})
configure_file(${SOURCE_DIR}/tools/cmake/PkgConfigApp.cpp ${app}/app.cpp COPYONLY)
run(sh -c "cd '${app}' && '${CXX}' ${CXX_FLAGS} ${rest} ${LINKER_FLAGS}")
execute_process(COMMAND ${app}/app RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "force at the end 0 N")
  message(FATAL_ERROR "the program README's line built (${line}) failed (${rc}):\n${out}")
endif()
message(STATUS "README's line built and ran a program: ${line}\n${out}")
execute_process(COMMAND ${PKG_CONFIG} --variable=includedir hapto OUTPUT_VARIABLE inc
                OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT EXISTS ${inc}/hapto/Version.h)
  message(FATAL_ERROR "pkg-config's includedir (${inc}) does not hold hapto/Version.h")
endif()

# 5. One library's pkg-config file links that library and what it needs, nothing more: the
#    index program builds with hapto-index.pc alone, which names no USB, HTTP or mesh library;
#    the view program builds with hapto-view.pc.
execute_process(COMMAND ${PKG_CONFIG} --cflags --libs hapto-index RESULT_VARIABLE rc
                OUTPUT_VARIABLE flags ERROR_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0 OR flags MATCHES "usb|httplib|meshoptimizer|hapto_devices|hapto_view")
  message(FATAL_ERROR "pkg-config --cflags --libs hapto-index (${rc}): ${flags}")
endif()
set(index_app ${WORK_DIR}/pkg-config-index)
file(MAKE_DIRECTORY ${index_app})
# pkg_config_program(<name> <source> <pkg-config module>): built in index_app with its flags.
function(pkg_config_program name source module)
  run(sh -c "cd '${index_app}' && '${CXX}' ${CXX_FLAGS} '${source}' \
             $(${PKG_CONFIG} --cflags --libs ${module}) -o ${name} ${LINKER_FLAGS}")
endfunction()
pkg_config_program(index ${SOURCE_DIR}/tools/cmake/consumers/index/main.cpp hapto-index)
run(${index_app}/index)
message(STATUS "hapto-index.pc: ${flags}")
# And hapto-view.pc links the program serving the view (cpp-httplib through it).
pkg_config_program(view ${SOURCE_DIR}/tools/cmake/consumers/view/main.cpp hapto-view)
run(${index_app}/view)
