# adaptseg_find_opencv(<module>...): OpenCV 4 with the given modules (core, imgproc, ...), as the
# imported targets opencv_<module> that adaptseg's targets link.
#
# Through OpenCV's own CMake config where it is installed (Debian: libopencv-dev, which depends
# on every OpenCV module, about 400 packages on a bare system). Otherwise through the headers and
# libraries of the modules' own Debian packages (libopencv-core-dev, libopencv-imgproc-dev,
# libopencv-imgcodecs-dev, libopencv-dnn-dev: about half as many packages, and no config file):
# imported targets of the same names, so that the build and an installed adaptseg's users link
# the same way either way. Sets OpenCV_FOUND. Set OpenCV_DIR for another installation with a
# config, or CMAKE_PREFIX_PATH for one without; CMAKE_DISABLE_FIND_PACKAGE_OpenCV hides both.
macro(adaptseg_find_opencv)
  find_package(OpenCV 4 QUIET COMPONENTS ${ARGV})
  if(NOT OpenCV_FOUND AND NOT CMAKE_DISABLE_FIND_PACKAGE_OpenCV)
    find_path(ADAPTSEG_OPENCV_INCLUDE_DIR NAMES opencv2/core/version.hpp PATH_SUFFIXES opencv4)
    mark_as_advanced(ADAPTSEG_OPENCV_INCLUDE_DIR)
    set(OpenCV_FOUND FALSE)
    if(ADAPTSEG_OPENCV_INCLUDE_DIR)
      file(STRINGS "${ADAPTSEG_OPENCV_INCLUDE_DIR}/opencv2/core/version.hpp" _adaptseg_cv_major
           REGEX "^#define CV_VERSION_MAJOR +[0-9]+")
      string(REGEX REPLACE "^#define CV_VERSION_MAJOR +([0-9]+).*" "\\1" _adaptseg_cv_major "${_adaptseg_cv_major}")
      if(_adaptseg_cv_major EQUAL 4)
        set(OpenCV_FOUND TRUE)
      endif()
    endif()
    foreach(_adaptseg_cv_module IN ITEMS ${ARGV})
      find_library(ADAPTSEG_OPENCV_${_adaptseg_cv_module}_LIBRARY NAMES opencv_${_adaptseg_cv_module})
      mark_as_advanced(ADAPTSEG_OPENCV_${_adaptseg_cv_module}_LIBRARY)
      if(NOT ADAPTSEG_OPENCV_${_adaptseg_cv_module}_LIBRARY
         OR NOT EXISTS "${ADAPTSEG_OPENCV_INCLUDE_DIR}/opencv2/${_adaptseg_cv_module}.hpp")
        set(OpenCV_FOUND FALSE)
      endif()
    endforeach()
    if(OpenCV_FOUND)
      foreach(_adaptseg_cv_module IN ITEMS ${ARGV})
        if(NOT TARGET opencv_${_adaptseg_cv_module})
          add_library(opencv_${_adaptseg_cv_module} UNKNOWN IMPORTED)
          set_target_properties(opencv_${_adaptseg_cv_module} PROPERTIES
            IMPORTED_LOCATION "${ADAPTSEG_OPENCV_${_adaptseg_cv_module}_LIBRARY}"
            INTERFACE_INCLUDE_DIRECTORIES "${ADAPTSEG_OPENCV_INCLUDE_DIR}")
        endif()
      endforeach()
    endif()
  endif()
endmacro()
