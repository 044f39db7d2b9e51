# hapto's libraries, what each needs of the others, and the packages each finds: written once,
# used to build a part of hapto (HAPTO_MODULES) and to write the installed haptoConfig.cmake, so
# `find_package(hapto COMPONENTS index)` finds exactly what hapto::index needs.

# The libraries in build order (an arrow never points back up: docs/DESIGN.md), each with the
# ones it links directly.
set(HAPTO_ALL_MODULES core io scenes index dynamics devices runtime experiments view)
set(HAPTO_MODULE_NEEDS_core "")
set(HAPTO_MODULE_NEEDS_io core)
set(HAPTO_MODULE_NEEDS_scenes core io)
set(HAPTO_MODULE_NEEDS_index core scenes)
set(HAPTO_MODULE_NEEDS_dynamics core index scenes)
set(HAPTO_MODULE_NEEDS_devices core io scenes)
set(HAPTO_MODULE_NEEDS_runtime core index dynamics devices scenes)
set(HAPTO_MODULE_NEEDS_experiments runtime index devices scenes)
set(HAPTO_MODULE_NEEDS_view runtime devices scenes)

# hapto_module_closure(<out> <module>...): the modules named and every one they need, in
# build order.
function(hapto_module_closure out)
  set(wanted ${ARGN})
  set(todo ${ARGN})
  while(todo)
    list(POP_FRONT todo module)
    if(NOT module IN_LIST HAPTO_ALL_MODULES)
      message(FATAL_ERROR "hapto: no module '${module}' (the modules: ${HAPTO_ALL_MODULES})")
    endif()
    foreach(need ${HAPTO_MODULE_NEEDS_${module}})
      if(NOT need IN_LIST wanted)
        list(APPEND wanted ${need})
        list(APPEND todo ${need})
      endif()
    endforeach()
  endwhile()
  set(ordered "")
  foreach(module ${HAPTO_ALL_MODULES})
    if(module IN_LIST wanted)
      list(APPEND ordered ${module})
    endif()
  endforeach()
  set(${out} ${ordered} PARENT_SCOPE)
endfunction()

# hapto_find_package(<module> <Package> [version] [args...]): find_package(... REQUIRED) for the
# module that links the package, its targets global (tests and tools link them too), and the
# same call recorded for that component of the installed package.
macro(hapto_find_package module package)
  find_package(${package} ${ARGN} REQUIRED GLOBAL)
  string(JOIN "|" _hapto_dependency package ${package} ${ARGN})
  set_property(GLOBAL APPEND PROPERTY HAPTO_DEPENDENCIES_${module} "${_hapto_dependency}")
endmacro()

# hapto_find_pkgconfig(<module> <PREFIX> <pkg-config module>): pkg_check_modules' imported
# target PkgConfig::<PREFIX> for the module, recorded like hapto_find_package.
macro(hapto_find_pkgconfig module prefix pcmodule)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(${prefix} REQUIRED IMPORTED_TARGET GLOBAL ${pcmodule})
  set_property(GLOBAL APPEND PROPERTY HAPTO_DEPENDENCIES_${module}
               "pkgconfig|${prefix}|${pcmodule}")
endmacro()

# hapto_config_components(<out> <module>...): the text haptoConfig.cmake.in takes as
# @HAPTO_CONFIG_COMPONENTS@: per module, the modules it needs and its recorded dependencies.
function(hapto_config_components out)
  set(text "set(_hapto_modules ${ARGN})\n")
  foreach(module ${ARGN})
    get_property(dependencies GLOBAL PROPERTY HAPTO_DEPENDENCIES_${module})
    list(REMOVE_DUPLICATES dependencies)
    string(APPEND text "set(_hapto_${module}_needs ${HAPTO_MODULE_NEEDS_${module}})\n"
                       "set(_hapto_${module}_dependencies \"${dependencies}\")\n")
  endforeach()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# hapto_check_module_links(<module>...): each module's CMakeLists links exactly the hapto
# modules the table above says (the table is what builds a part of hapto and what the
# installed package's components pull in, so it must not drift from the link lines).
function(hapto_check_module_links)
  foreach(module ${ARGN})
    get_target_property(links hapto_${module} LINK_LIBRARIES)
    set(linked "")
    foreach(link ${links})
      if(link MATCHES "^hapto::(.+)$")
        list(APPEND linked ${CMAKE_MATCH_1})
      endif()
    endforeach()
    set(table ${HAPTO_MODULE_NEEDS_${module}})
    list(SORT linked)
    list(SORT table)
    if(NOT "${linked}" STREQUAL "${table}")
      message(FATAL_ERROR "hapto_${module} links hapto modules '${linked}' but "
                          "tools/cmake/HaptoModules.cmake says '${table}'; make them agree")
    endif()
  endforeach()
endfunction()

# How a package a module found is named on a pkg-config line: a pkg-config module for Requires,
# or flags for Libs (meshoptimizer has no .pc file in Debian 12).
set(HAPTO_PC_REQUIRES_glm glm)
set(HAPTO_PC_REQUIRES_nlohmann_json nlohmann_json)
set(HAPTO_PC_REQUIRES_TBB tbb)
set(HAPTO_PC_REQUIRES_simdjson simdjson)
set(HAPTO_PC_REQUIRES_Qhull qhull_r)
set(HAPTO_PC_LIBS_Threads -pthread)
set(HAPTO_PC_LIBS_meshoptimizer -lmeshoptimizer)

# hapto_write_pkgconfig(<module>): writes and installs hapto-<module>.pc. The libraries are
# static (unless built with BUILD_SHARED_LIBS), so what a module links privately is in its
# Requires and Libs, not Requires.private: the plain `pkg-config --libs` gives a complete
# link line (`--static` would also ask for the dependencies' own static dependencies).
function(hapto_write_pkgconfig module)
  list(TRANSFORM HAPTO_MODULE_NEEDS_${module} PREPEND hapto- OUTPUT_VARIABLE requires)
  set(libs -lhapto_${module})
  get_property(dependencies GLOBAL PROPERTY HAPTO_DEPENDENCIES_${module})
  foreach(dependency ${dependencies})
    string(REPLACE "|" ";" dependency "${dependency}")
    list(GET dependency 1 name)
    if(dependency MATCHES "^pkgconfig;")
      list(GET dependency 2 name)
      list(APPEND requires ${name})
    elseif(DEFINED HAPTO_PC_REQUIRES_${name})
      list(APPEND requires ${HAPTO_PC_REQUIRES_${name}})
    elseif(DEFINED HAPTO_PC_LIBS_${name})
      list(APPEND libs ${HAPTO_PC_LIBS_${name}})
    else()
      message(FATAL_ERROR "hapto_write_pkgconfig: how does pkg-config name ${name}?")
    endif()
  endforeach()
  if(module STREQUAL "devices")
    # The PHANToM backend's dlopen (libdl where the C library does not hold it).
    list(TRANSFORM CMAKE_DL_LIBS PREPEND -l OUTPUT_VARIABLE dl)
    list(APPEND libs ${dl})
  endif()
  set(cflags "")
  if(module STREQUAL "core")
    # Our headers are C++20; GLM's settings as hapto_glm has them.
    set(cflags "-std=c++20 -DGLM_ENABLE_EXPERIMENTAL")
  endif()
  list(REMOVE_DUPLICATES requires)
  list(REMOVE_DUPLICATES libs)
  list(JOIN requires " " HAPTO_PC_REQUIRES)
  list(JOIN libs " " HAPTO_PC_LIBS)
  set(HAPTO_PC_NAME hapto-${module})
  set(HAPTO_PC_CFLAGS "${cflags}")
  configure_file(${PROJECT_SOURCE_DIR}/tools/cmake/hapto-module.pc.in
                 ${PROJECT_BINARY_DIR}/pkgconfig/hapto-${module}.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/hapto-${module}.pc
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endfunction()
