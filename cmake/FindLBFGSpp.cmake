# Finds LBFGSpp (header-only L-BFGS-B, https://github.com/yixuan/LBFGSpp; Debian:
# liblbfgspp-dev), which adaptseg's Gaussian process uses through
# include/adaptseg/core/detail/lbfgs.hpp. Supported: 0.1.0 (see that header).
#
# Defines the imported target LBFGSpp::LBFGSpp (its headers and Eigen3::Eigen) and
# LBFGSpp_FOUND, LBFGSpp_INCLUDE_DIR. Set LBFGSpp_ROOT or CMAKE_PREFIX_PATH to point at
# another installation.
find_path(LBFGSpp_INCLUDE_DIR NAMES LBFGSB.h PATH_SUFFIXES include)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(LBFGSpp REQUIRED_VARS LBFGSpp_INCLUDE_DIR)
if(LBFGSpp_FOUND AND NOT TARGET LBFGSpp::LBFGSpp)
  add_library(LBFGSpp::LBFGSpp INTERFACE IMPORTED)
  set_target_properties(LBFGSpp::LBFGSpp PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${LBFGSpp_INCLUDE_DIR}")
  if(TARGET Eigen3::Eigen)
    set_property(TARGET LBFGSpp::LBFGSpp PROPERTY INTERFACE_LINK_LIBRARIES Eigen3::Eigen)
  endif()
endif()
mark_as_advanced(LBFGSpp_INCLUDE_DIR)
