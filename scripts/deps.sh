#!/usr/bin/env bash
# Installs the Debian packages adaptseg needs, or says which are missing.
#   scripts/deps.sh build   compiler, CMake and the C++ libraries (library, examples, tests)
#   scripts/deps.sh test    build + what the test suite runs (Python for the data converters,
#                           matplotlib for the figures cli:adaptseg_evaluate:unseen_tile checks,
#                           GDAL's ogrinfo, gdalinfo, gdal_translate, gdaltransform for the
#                           exports and GeoTIFF fields, doxygen for docs:doxygen, pyflakes3,
#                           clang-format and clang-tidy for the lint tests, Clang's front end
#                           for headers:alone)
#   scripts/deps.sh docs    doxygen, for the API reference (scripts/docs.sh)
#   scripts/deps.sh bench   test + what the benchmarks compare against (scikit-learn, with
#                           OpenBLAS as well as the reference BLAS)
#   scripts/deps.sh plots   build + matplotlib for the evaluation figures
#   scripts/deps.sh demo    what scripts/demo.sh builds and runs, and no more: the example
#                           programs' libraries with OpenCV's four modules as their own packages
#                           (no libopencv-dev, which brings every module; no GDAL), and matplotlib
#   scripts/deps.sh fuzz    build + clang with libFuzzer (scripts/fuzz.sh)
# As root it runs apt-get; otherwise it prints the command to run and fails if anything is missing.
#   scripts/deps.sh SET --list   prints the set's packages, one per line, and installs nothing
#                                (scripts/apt_footprint.sh counts what they bring on a bare system)
set -euo pipefail

# libopencv-dev: the only package that ships OpenCV's CMake config (OpenCVConfig.cmake).
# libgeographiclib-dev: geo-reference and mission export (adaptseg::geo).
# libgdal-dev: GeoTIFF fields and georeferenced maps (adaptseg::gdal; optional to the build).
build=(cmake g++ make pkg-config libeigen3-dev libopencv-dev doctest-dev liblbfgspp-dev
       libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libgeographiclib-dev libgdal-dev)
python=(python3 python3-numpy python3-opencv python3-yaml python3-pil)
# The demo: OpenCV's modules found without its CMake config (cmake/adaptsegFindOpenCV.cmake).
demo=(cmake g++ make libeigen3-dev liblbfgspp-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
      libgeographiclib-dev libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-dnn-dev
      python3 python3-matplotlib)
case "${1:-build}" in
  build) want=("${build[@]}") ;;
  test) want=("${build[@]}" "${python[@]}" python3-matplotlib gdal-bin doxygen pyflakes3 clang-format-14 clang-tidy-14 clang-14) ;;
  docs) want=(doxygen) ;;
  bench) want=("${build[@]}" "${python[@]}" gdal-bin doxygen python3-sklearn python3-torch libopenblas0-pthread) ;;
  plots) want=("${build[@]}" "${python[@]}" python3-matplotlib) ;;
  demo) want=("${demo[@]}") ;;
  # clang: the compiler; libclang-rt-14-dev: libFuzzer and the sanitizer runtimes for it.
  fuzz) want=("${build[@]}" clang libclang-rt-14-dev) ;;
  *) echo "usage: $0 [build|test|docs|bench|plots|demo|fuzz]" >&2; exit 2 ;;
esac

if [ "${2:-}" = --list ]; then
  printf '%s\n' "${want[@]}"
  exit 0
fi

missing=()
for p in "${want[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  echo "deps.sh: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "deps.sh: missing Debian packages: ${missing[*]}" >&2
  echo "deps.sh: install them with: sudo apt-get install ${missing[*]}" >&2
  exit 1
fi
