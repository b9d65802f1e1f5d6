// Fuzz target: Field::load on an arbitrary field.yaml, in a directory that also holds a
// valid labels.png (16 x 12, classes 0..2 and ignore pixels), a matching image.png and a
// mismatched small.png, so that inputs naming them reach the image checks.

#include "fuzz_support.hpp"

#include <adaptseg/vision/field.hpp>

#include <opencv2/imgcodecs.hpp>

#include <cstddef>
#include <cstdint>

namespace {

const std::filesystem::path& field_dir() {
  static const std::filesystem::path dir = [] {
    const auto d = adaptseg::fuzz::scratch_dir() / "field";
    std::filesystem::create_directories(d);
    cv::Mat labels(12, 16, CV_8UC1);
    for (int r = 0; r < labels.rows; ++r)
      for (int c = 0; c < labels.cols; ++c)
        labels.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(c < 2 ? 255 : (r + c) % 3);
    if (!cv::imwrite((d / "labels.png").string(), labels) ||
        !cv::imwrite((d / "image.png").string(), cv::Mat(12, 16, CV_8UC3, cv::Scalar(0, 120, 0))) ||
        !cv::imwrite((d / "small.png").string(), cv::Mat(6, 8, CV_8UC3, cv::Scalar(0, 0, 90))))
      std::abort();
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto& dir = field_dir();
  adaptseg::fuzz::write_bytes(dir / "field.yaml", data, size);
  adaptseg::fuzz::expect_clean([&] { (void)adaptseg::Field::load(dir); });
  return 0;
}
