#pragma once
/// @file
/// The simulated nadir camera over a Field (docs/method.md, "Decisions where the paper is silent,
/// and departures"): crop the footprint from the
/// orthomosaic and resample it to the camera's pixel grid.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace adaptseg {

/// Renders camera images of a Field.
///
/// The footprint of a waypoint is snapped to whole orthomosaic pixels (Field::pixel_rect),
/// so adjacent footprints tile the orthomosaic exactly. The RGB crop is resampled with area
/// interpolation; labels are never interpolated (they are passed on at full resolution for
/// the oracle and the metrics). Parts outside the orthomosaic are black / ignore.
class SimulatedSensor {
 public:
  /// Largest footprint capture() renders [orthomosaic pixels] (2^28).
  static constexpr double kMaxFootprintPixels = 268435456.0;

  /// @throws std::invalid_argument via CameraModel for an invalid camera.
  SimulatedSensor(Field field, CameraModel camera) : field_(std::move(field)), camera_(camera) {}

  [[nodiscard]] const Field& field() const noexcept { return field_; }
  [[nodiscard]] const CameraModel& camera() const noexcept { return camera_; }

  /// The image taken at waypoint `w`, the camera turned by `yaw_deg` (Image::yaw_deg; the
  /// planners fly 0): the footprint's orthomosaic pixels are cut out in the camera's
  /// orientation (nearest neighbour: each footprint-grid point takes the orthomosaic pixel it
  /// lies in), the colour then resampled as at yaw 0.
  /// @throws std::invalid_argument if the waypoint's GSD is finer than the orthomosaic's
  ///         (the simulator would have to invent detail), its footprint is empty, or the
  ///         footprint exceeds kMaxFootprintPixels, or for a yaw that is not finite.
  [[nodiscard]] Image capture(const Waypoint& w, double yaw_deg = 0.0) const {
    detail::require(w.gsd_cm >= field_.gsd_cm() * (1.0 - 1e-9),
                    "SimulatedSensor::capture: waypoint GSD [cm/px] is finer than the field's " +
                        std::to_string(field_.gsd_cm()) + " cm/px",
                    w.gsd_cm);
    // The footprint is cut out of the orthomosaic at its resolution: bound it before
    // allocating (an absurd altitude must be an error, not a terabyte allocation).
    const double fp_px =
        (w.footprint.width_m() * 100.0 / field_.gsd_cm()) * (w.footprint.height_m() * 100.0 / field_.gsd_cm());
    detail::require(std::isfinite(fp_px) && fp_px <= kMaxFootprintPixels,
                    "SimulatedSensor::capture: the footprint is too large to simulate (more than 2^28 "
                    "orthomosaic pixels: lower the altitude), waypoint gsd_cm",
                    w.gsd_cm);
    Image img;
    img.position = w.position;
    img.gsd_cm = w.gsd_cm;
    img.width_px = camera_.width_px();
    img.height_px = camera_.height_px();
    img.ignore_label = field_.ignore_label();
    img.footprint_px = field_.pixel_rect(w.footprint);
    detail::require(img.footprint_px.width > 0 && img.footprint_px.height > 0,
                    "SimulatedSensor::capture: footprint covers no orthomosaic pixel", w.gsd_cm);
    img.yaw_deg = yaw_deg;
    const FootprintFrame frame(img);
    const auto cut = [&](const cv::Mat& src, const cv::Scalar& fill) {
      return frame.turned() ? crop_turned(src, frame, img.footprint_px.size(), fill)
                            : crop(src, img.footprint_px, fill);
    };
    img.ground_truth = cut(field_.labels(), cv::Scalar(field_.ignore_label()));
    if (field_.has_image()) {
      // A footprint inside the orthomosaic is resampled where it lies, without a copy.
      const bool inside = !frame.turned() && (img.footprint_px & cv::Rect(0, 0, field_.image().cols,
                                                                          field_.image().rows)) == img.footprint_px;
      const cv::Mat rgb = inside ? field_.image()(img.footprint_px) : cut(field_.image(), cv::Scalar(0, 0, 0));
      cv::resize(rgb, img.bgr, cv::Size(img.width_px, img.height_px), 0, 0, cv::INTER_AREA);
    }
    return img;
  }

 private:
  /// `src(rect)`, with `fill` where the rectangle leaves the image.
  static cv::Mat crop(const cv::Mat& src, const cv::Rect& rect, const cv::Scalar& fill) {
    cv::Mat out(rect.size(), src.type(), fill);
    const cv::Rect inside = rect & cv::Rect(0, 0, src.cols, src.rows);
    if (inside.area() > 0) src(inside).copyTo(out(inside - rect.tl()));
    return out;
  }

  /// The footprint grid of `frame` (`size` points, row by row) cut out of `src` (8-bit, one or
  /// three channels): each point takes the pixel of `src` it lies in, `fill` outside `src`.
  static cv::Mat crop_turned(const cv::Mat& src, const FootprintFrame& frame, cv::Size size, const cv::Scalar& fill) {
    cv::Mat out(size, src.type(), fill);
    const auto bytes = src.elemSize();
    for (int r = 0; r < size.height; ++r) {
      auto* dst = out.ptr<unsigned char>(r);
      for (int c = 0; c < size.width; ++c) {
        const cv::Point2d p = frame.to_map(c + 0.5, r + 0.5);
        const double x = std::floor(p.x), y = std::floor(p.y);
        if (x < 0.0 || y < 0.0 || x >= src.cols || y >= src.rows) continue;
        const auto* px = src.ptr<unsigned char>(static_cast<int>(y)) + static_cast<std::size_t>(x) * bytes;
        std::copy(px, px + bytes, dst + static_cast<std::size_t>(c) * bytes);
      }
    }
    return out;
  }

  Field field_;
  CameraModel camera_;
};

}  // namespace adaptseg
