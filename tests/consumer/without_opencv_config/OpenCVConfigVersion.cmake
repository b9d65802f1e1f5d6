# Accepts any version request, so that CMake loads the stand-in config beside it and looks no further.
set(PACKAGE_VERSION "4.0.0")
set(PACKAGE_VERSION_COMPATIBLE TRUE)
