# Find SuiteSparse's CHOLMOD and UMFPACK (Debian libsuitesparse-dev) for the static solver.
#
# Defines the imported targets SuiteSparse::CHOLMOD and SuiteSparse::UMFPACK, the names
# SuiteSparse ≥ 7 gives them in its own CMake packages (used when present); SuiteSparse 5
# (Debian 12) ships neither CMake packages nor pkg-config files, so the libraries and headers are
# looked up directly. libpd's package configuration (libpdConfig.cmake) runs this module again,
# because a static libpd names the targets in its link interface.
#
# Result: LibpdSuiteSparse_FOUND.
include(FindPackageHandleStandardArgs)

if(NOT TARGET SuiteSparse::CHOLMOD)
  find_package(CHOLMOD CONFIG QUIET)
endif()
if(NOT TARGET SuiteSparse::UMFPACK)
  find_package(UMFPACK CONFIG QUIET)
endif()

foreach(lib CHOLMOD UMFPACK)
  string(TOLOWER ${lib} name)
  if(NOT TARGET SuiteSparse::${lib})
    find_path(LibpdSuiteSparse_${lib}_INCLUDE_DIR ${name}.h PATH_SUFFIXES suitesparse)
    find_library(LibpdSuiteSparse_${lib}_LIBRARY ${name})
    mark_as_advanced(LibpdSuiteSparse_${lib}_INCLUDE_DIR LibpdSuiteSparse_${lib}_LIBRARY)
    if(LibpdSuiteSparse_${lib}_INCLUDE_DIR AND LibpdSuiteSparse_${lib}_LIBRARY)
      add_library(SuiteSparse::${lib} UNKNOWN IMPORTED)
      set_target_properties(SuiteSparse::${lib} PROPERTIES
        IMPORTED_LOCATION "${LibpdSuiteSparse_${lib}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${LibpdSuiteSparse_${lib}_INCLUDE_DIR}")
    endif()
  endif()
  if(TARGET SuiteSparse::${lib})
    set(LibpdSuiteSparse_${lib}_TARGET SuiteSparse::${lib})
  endif()
endforeach()

find_package_handle_standard_args(LibpdSuiteSparse
  REQUIRED_VARS LibpdSuiteSparse_CHOLMOD_TARGET LibpdSuiteSparse_UMFPACK_TARGET)
