# Finds GeographicLib (https://geographiclib.sourceforge.io) and defines the imported target
# GeographicLib::GeographicLib.
#
# GeographicLib built with CMake installs a package config that defines that target; use it
# when there is one. Debian's libgeographiclib-dev ships no config, only a find module outside
# CMake's module path (/usr/share/cmake/geographiclib) that sets variables but no target, so
# otherwise look for the header and the library directly.
find_package(GeographicLib CONFIG QUIET)
if(TARGET GeographicLib::GeographicLib)
  set(GeographicLib_FOUND TRUE)
  return()
endif()

find_path(GeographicLib_INCLUDE_DIR GeographicLib/LocalCartesian.hpp)
find_library(GeographicLib_LIBRARY NAMES GeographicLib)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(GeographicLib REQUIRED_VARS GeographicLib_LIBRARY GeographicLib_INCLUDE_DIR)
mark_as_advanced(GeographicLib_INCLUDE_DIR GeographicLib_LIBRARY)
if(GeographicLib_FOUND AND NOT TARGET GeographicLib::GeographicLib)
  add_library(GeographicLib::GeographicLib UNKNOWN IMPORTED)
  set_target_properties(GeographicLib::GeographicLib PROPERTIES
    IMPORTED_LOCATION "${GeographicLib_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${GeographicLib_INCLUDE_DIR}")
endif()
