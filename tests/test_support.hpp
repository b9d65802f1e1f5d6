#pragma once
// Helpers shared by the tests: synthetic fields, temporary directories, bundled data paths.

#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/vision/field.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include <unistd.h>

namespace adaptseg::test {

/// Mission options whose times do not depend on the machine: 0.1 s charged per image, nothing
/// for planning (the oracle sweeps' setting).
inline MissionOptions deterministic_options() {
  MissionOptions o;
  o.fixed_segmentation_time_s = 0.1;
  o.fixed_planning_time_s = 0.0;
  return o;
}

/// Path of a bundled example field (examples/data/NAME).
inline std::filesystem::path example_field(const std::string& name) {
  return std::filesystem::path(ADAPTSEG_EXAMPLES_DIR) / "data" / name;
}

/// A fresh empty directory under the system temp dir, removed by the destructor.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("adaptseg-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline void write_file(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The three WeedMap classes.
inline std::vector<ClassInfo> soil_crop_weed() {
  return {{"soil", {0, 0, 0}}, {"crop", {0, 255, 0}}, {"weed", {255, 0, 0}}};
}

/// A random field of blobs: soil background, crop and weed squares of various sizes, a
/// border of ignore pixels. Deterministic for a given seed.
inline Field blob_field(int width, int height, double gsd_cm, unsigned seed = 7, int border = 0) {
  cv::Mat labels(height, width, CV_8UC1, cv::Scalar(0));
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), size(1, 12), cls(1, 2);
  for (int i = 0; i < width * height / 200; ++i) {
    const int s = size(rng);
    cv::rectangle(labels, cv::Rect(x(rng), y(rng), s, s), cv::Scalar(cls(rng)), cv::FILLED);
  }
  if (border > 0) {
    labels.rowRange(0, border).setTo(255);
    labels.colRange(0, border).setTo(255);
  }
  return Field("blobs", gsd_cm, labels, soil_crop_weed(), {1, 2});
}

/// Two top-level regions (3.0 cm/px with the default camera over 2880 x 1080 px at 1 cm/px)
/// and one crop patch in the first region's top-left sub-cell (at 1.0 cm/px a region is 3 x 3
/// sub-cells of 480 x 360 px): what DescentCoverage::interest is tested on.
inline Field patch_field() {
  cv::Mat labels(1080, 2880, CV_8UC1, cv::Scalar(0));
  labels(cv::Rect(50, 50, 100, 100)).setTo(1);
  return Field("patch", 1.0, labels, soil_crop_weed(), {1, 2});
}

/// Writes `labels` and a field.yaml with `yaml_body` (everything but the labels line) to `dir`.
inline void write_field(const std::filesystem::path& dir, const cv::Mat& labels, const std::string& yaml) {
  std::filesystem::create_directories(dir);
  cv::imwrite((dir / "labels.png").string(), labels);
  write_file(dir / "field.yaml", yaml);
}

inline const char* kWeedYaml = R"(name: tiny
gsd_cm: 1.0
labels: labels.png
ignore_label: 255
classes:
  - {name: soil, color: [0, 0, 0]}
  - {name: crop, color: [0, 255, 0]}
  - {name: weed, color: [255, 0, 0]}
interest: [crop, weed]
)";

}  // namespace adaptseg::test
