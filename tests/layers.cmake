# The components' layers (cmake -DINCLUDE_DIR=<repo>/include/adaptseg -P layers.cmake): every
# header of a component folder (and its umbrella header) includes only adaptseg headers of its
# own component and of those below it, and only the libraries its CMake target links:
#   core   (adaptseg::adaptseg) Eigen, LBFGSpp
#   vision (adaptseg::vision)   + OpenCV core/imgproc/imgcodecs, yaml-cpp
#   erfnet (adaptseg::erfnet)   + OpenCV DNN
#   geo    (adaptseg::geo)      vision's + GeographicLib, nlohmann_json
#   gdal   (adaptseg::gdal)     geo's + GDAL
#   sim    (adaptseg::sim)      vision's: the experiment layer (strategies flown in simulation)
#   mavlink (adaptseg::mavlink) no library: the C++ standard library only (core's headers allowed,
#                               but its target gives no Eigen)
# One line per breach, naming the header, the include and the component; fails if any.
cmake_minimum_required(VERSION 3.21)
if(NOT INCLUDE_DIR)
  message(FATAL_ERROR "usage: cmake -DINCLUDE_DIR=<repo>/include/adaptseg -P layers.cmake")
endif()
# component ! adaptseg folders it may include ! library include prefixes it may use (regex)
set(_rules
  "core!core!^$"
  "vision!core vision!^(opencv2/(core|imgproc|imgcodecs)|yaml-cpp/)"
  "erfnet!core vision erfnet!^(opencv2/|yaml-cpp/)"
  "geo!core vision geo!^(opencv2/(core|imgproc|imgcodecs)|yaml-cpp/|GeographicLib/|nlohmann/)"
  "gdal!core vision geo gdal!^(opencv2/(core|imgproc|imgcodecs)|yaml-cpp/|GeographicLib/|nlohmann/|gdal|cpl_|ogr)"
  "mavlink!core mavlink!^$"
  "sim!core vision sim!^(opencv2/(core|imgproc|imgcodecs)|yaml-cpp/)")
# What counts as a library (anything else is the standard library, Eigen, LBFGSpp or an intrinsic).
set(_library "^(opencv2/|yaml-cpp/|GeographicLib/|nlohmann/|gdal|cpl_|ogr)")
set(_breaches 0)
set(_checked 0)
foreach(_rule IN LISTS _rules)
  string(REPLACE "!" ";" _rule "${_rule}")
  list(GET _rule 0 _component)
  list(GET _rule 1 _allowed)
  list(GET _rule 2 _libraries)
  string(REPLACE " " ";" _allowed "${_allowed}")
  file(GLOB_RECURSE _headers "${INCLUDE_DIR}/${_component}/*.hpp")
  list(APPEND _headers "${INCLUDE_DIR}/${_component}.hpp")
  if(_component STREQUAL "vision")
    list(APPEND _headers "${INCLUDE_DIR}/planner.hpp")
  endif()
  foreach(_header IN LISTS _headers)
    if(NOT EXISTS "${_header}")
      message(SEND_ERROR "${_header}: missing (the umbrella header of component ${_component})")
      math(EXPR _breaches "${_breaches} + 1")
      continue()
    endif()
    math(EXPR _checked "${_checked} + 1")
    file(STRINGS "${_header}" _includes REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    foreach(_line IN LISTS _includes)
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]*)[>\"].*$" "\\1" _path "${_line}")
      if(_path MATCHES "^adaptseg/")
        set(_ok FALSE)
        foreach(_below IN LISTS _allowed)
          if(_path MATCHES "^adaptseg/${_below}(/|\\.hpp$)")
            set(_ok TRUE)
          endif()
        endforeach()
        if(_path STREQUAL "adaptseg/planner.hpp")
          set(_ok FALSE)  # the umbrella of vision; no component header includes it
        endif()
      elseif(_path MATCHES "${_library}")
        set(_ok FALSE)
        if(_path MATCHES "${_libraries}")
          set(_ok TRUE)
        endif()
      else()
        set(_ok TRUE)
      endif()
      if(NOT _ok)
        file(RELATIVE_PATH _rel "${INCLUDE_DIR}/.." "${_header}")
        message(SEND_ERROR "${_rel}: includes <${_path}>, which component ${_component} may not use")
        math(EXPR _breaches "${_breaches} + 1")
      endif()
    endforeach()
  endforeach()
endforeach()
file(GLOB _stray "${INCLUDE_DIR}/*.hpp")
foreach(_header IN LISTS _stray)
  get_filename_component(_name "${_header}" NAME_WE)
  if(NOT _name MATCHES "^(core|vision|erfnet|geo|gdal|mavlink|sim|planner)$")
    message(SEND_ERROR "adaptseg/${_name}.hpp: a header outside the component folders")
    math(EXPR _breaches "${_breaches} + 1")
  endif()
endforeach()
if(_breaches GREATER 0)
  message(FATAL_ERROR "${_breaches} breach(es) of the components' layers")
endif()
message(STATUS "layers: ${_checked} headers include only their own and lower components")
