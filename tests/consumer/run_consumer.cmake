# Installs the build tree into a scratch prefix, then configures, builds and runs the consumer
# projects against it. Called by CTest with BUILD_DIR, SOURCE_DIR and WORK_DIR.
#   - SOURCE_DIR: every component (vision, erfnet, geo; gdal where installed) asked for and used;
#   - SOURCE_DIR again with OpenCV's CMake config replaced by one that finds nothing (the modules
#     found by cmake/adaptsegFindOpenCV.cmake), the network component built and run;
#   - SOURCE_DIR/core: the core alone with OpenCV, yaml-cpp, nlohmann_json and GeographicLib
#     hidden (a GP fitted); asking for vision there must fail, naming OpenCV.

# step(WHAT ARGS...): runs ARGS as a command; stops the test naming WHAT if it fails.
function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${what} failed: ${rc}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix")
step("install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")

step("configuring the consumer" "${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${WORK_DIR}/build" ${prefix}
     -DCMAKE_BUILD_TYPE=Release)
step("building the consumer" "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")
set(exes consumer consumer_core consumer_geo consumer_sim consumer_erfnet)
if(EXISTS "${WORK_DIR}/prefix/share/cmake/adaptseg/adaptsegGdalTargets.cmake")  # installed with GDAL
  list(APPEND exes consumer_gdal)
endif()
foreach(exe IN LISTS exes)
  step("${exe}" "${WORK_DIR}/build/${exe}")
endforeach()

# Without OpenCV's CMake config (Debian's libopencv-core-dev, ... ship none; scripts/deps.sh demo
# installs those): the package finds the modules by their headers and libraries.
step("configuring the consumer without OpenCV's config" "${CMAKE_COMMAND}" -S "${SOURCE_DIR}"
     -B "${WORK_DIR}/no-opencv-config" ${prefix} -DCMAKE_BUILD_TYPE=Release
     "-DOpenCV_DIR=${SOURCE_DIR}/without_opencv_config")
file(STRINGS "${WORK_DIR}/no-opencv-config/CMakeCache.txt" include_dir REGEX "^ADAPTSEG_OPENCV_INCLUDE_DIR:")
if(NOT include_dir MATCHES "opencv4$")
  message(FATAL_ERROR "without OpenCV's config the package did not find its headers itself: '${include_dir}'")
endif()
step("building the consumer without OpenCV's config" "${CMAKE_COMMAND}" --build "${WORK_DIR}/no-opencv-config"
     --target consumer_erfnet)
step("consumer_erfnet without OpenCV's config" "${WORK_DIR}/no-opencv-config/consumer_erfnet")

set(hidden -DCMAKE_DISABLE_FIND_PACKAGE_OpenCV=ON -DCMAKE_DISABLE_FIND_PACKAGE_yaml-cpp=ON
           -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON -DCMAKE_DISABLE_FIND_PACKAGE_GeographicLib=ON)
step("configuring the core consumer with the other dependencies hidden" "${CMAKE_COMMAND}" -S "${SOURCE_DIR}/core"
     -B "${WORK_DIR}/core" ${prefix} -DCMAKE_BUILD_TYPE=Release ${hidden})
step("building the core consumer" "${CMAKE_COMMAND}" --build "${WORK_DIR}/core")
step("core_only" "${WORK_DIR}/core/core_only")

execute_process(COMMAND "${CMAKE_COMMAND}" -S "${SOURCE_DIR}/core" -B "${WORK_DIR}/core-vision" ${prefix}
                        -DASK_VISION=ON ${hidden}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc OR NOT err MATCHES "adaptseg::vision needs OpenCV 4")
  message(FATAL_ERROR "asking for vision without OpenCV: rc ${rc}, want a failure naming OpenCV; got:\n${err}")
endif()
