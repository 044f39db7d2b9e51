# ctest "install: README's two_hands snippet and pkg-config line build against an installed hapto".
# Run as: cmake -DBINARY_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX=...
#         [-DLAUNCHER=...] [-DCXX_FLAGS=...] [-DLINKER_FLAGS=...] -P InstallTest.cmake
# Installs the build into WORK_DIR/prefix, configures and builds tools/examples/two_hands
# against it with find_package(hapto) (no CMAKE_CXX_STANDARD: C++20 must come from the
# exported targets), checks the README shows that CMakeLists.txt exactly, and that the
# pkg-config file, the udev rule, the licence and hapto/Version.h are installed; then builds
# tools/cmake/PkgConfigApp.cpp with README's pkg-config line and runs it.
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
foreach(f include/hapto/Version.h include/hapto/runtime/Runtime.h
          lib/udev/rules.d/99-hapto-falcon.rules share/licenses/hapto/LICENSE bin/hapto)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
file(GLOB pc ${prefix}/lib*/pkgconfig/hapto.pc ${prefix}/lib/*/pkgconfig/hapto.pc)
if(NOT pc)
  message(FATAL_ERROR "not installed: hapto.pc")
endif()
file(GLOB_RECURSE exported ${prefix}/*/haptoTargets.cmake)
file(READ "${exported}" targets)
foreach(internal hapto_warnings hapto_catch_main)
  if(targets MATCHES "${internal}")
    message(FATAL_ERROR "the exported targets name the build helper ${internal}")
  endif()
endforeach()

# 3. Build the example against the installed hapto, as an application would.
set(args -S ${example} -B ${WORK_DIR}/two_hands -G ${GENERATOR} -DCMAKE_CXX_COMPILER=${CXX}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
if(LAUNCHER)
  list(APPEND args -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
# The installed libraries carry the build's flags (a sanitizer preset's instrumentation): the
# application must be built and linked with them too.
if(CXX_FLAGS)
  list(APPEND args "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}")
endif()
if(LINKER_FLAGS)
  list(APPEND args "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
endif()
run(${CMAKE_COMMAND} ${args})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/two_hands)
message(STATUS "two_hands built against ${prefix}")

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
