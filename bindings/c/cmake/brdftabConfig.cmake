# CMake package of brdftab's C ABI, for `find_package(brdftab CONFIG)`: installed as
# $PREFIX/lib/cmake/brdftab/brdftabConfig.cmake beside brdftabConfigVersion.cmake
# (bindings/c/README.md, **Install**), it finds the header and libraries relative to itself,
# so a prefix can be moved. Two imported targets:
#   brdftab::brdftab         the shared library, libbrdftab_c.so
#   brdftab::brdftab_static  the archive, libbrdftab_c.a, with the system libraries it needs
# Linux's file names (the install steps are Linux's: README.md, "Platforms").
include(CMakeFindDependencyMacro)
find_dependency(Threads)

get_filename_component(_brdftab_prefix "${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
foreach(_brdftab_file IN ITEMS include/brdftab.h lib/libbrdftab_c.so lib/libbrdftab_c.a)
  if(NOT EXISTS "${_brdftab_prefix}/${_brdftab_file}")
    set(brdftab_FOUND FALSE)
    set(brdftab_NOT_FOUND_MESSAGE "brdftab: ${_brdftab_prefix}/${_brdftab_file} is missing")
    return()
  endif()
endforeach()

if(NOT TARGET brdftab::brdftab)
  add_library(brdftab::brdftab SHARED IMPORTED)
  set_target_properties(brdftab::brdftab PROPERTIES
    IMPORTED_LOCATION "${_brdftab_prefix}/lib/libbrdftab_c.so"
    # The library has no SONAME: linked as -lbrdftab_c, a program records `libbrdftab_c.so`
    # (not this prefix's path) and finds it through its rpath or the loader's paths.
    IMPORTED_NO_SONAME TRUE
    INTERFACE_INCLUDE_DIRECTORIES "${_brdftab_prefix}/include")
endif()
if(NOT TARGET brdftab::brdftab_static)
  add_library(brdftab::brdftab_static STATIC IMPORTED)
  set_target_properties(brdftab::brdftab_static PROPERTIES
    IMPORTED_LOCATION "${_brdftab_prefix}/lib/libbrdftab_c.a"
    INTERFACE_INCLUDE_DIRECTORIES "${_brdftab_prefix}/include"
    # brdftab.pc's Libs.private.
    INTERFACE_LINK_LIBRARIES "Threads::Threads;${CMAKE_DL_LIBS};m")
endif()
unset(_brdftab_file)
unset(_brdftab_prefix)
