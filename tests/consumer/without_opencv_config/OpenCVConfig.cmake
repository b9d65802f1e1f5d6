# A stand-in for OpenCV's CMake config that finds nothing (run_consumer.cmake points OpenCV_DIR
# here): as on a machine with only the OpenCV modules' own Debian packages, which ship no config,
# so that adaptseg's package has to find the modules through cmake/adaptsegFindOpenCV.cmake.
set(OpenCV_FOUND FALSE)
