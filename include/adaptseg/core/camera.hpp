#pragma once
/// @file
/// Pinhole nadir camera: ground sampling distance (GSD) <-> altitude, and footprint.

#include <adaptseg/core/error.hpp>

#include <string>

namespace adaptseg {

/// Ground extent of one image [m]: `width_m` along the image's x axis (its columns).
struct Extent {
  double width_m = 0.0;
  double height_m = 0.0;
};

/// Camera parameters; validated by CameraModel's constructor.
struct CameraParams {
  int image_width_px = 480;      ///< I_w [px]
  int image_height_px = 360;     ///< I_h [px]
  double sensor_width_mm = 4.8;  ///< S_w [mm]
  double focal_length_mm = 5.5;  ///< f [mm]
};

/// A camera looking straight down (docs/method.md, "Decisions where the paper is silent, and
/// departures"; paper §3.2, the GSD definition after
/// Eq. `eq:gp`): `GSD(h) = 100 * h * S_w / (f * I_w)` [cm/px] with h in m, S_w and f in mm.
/// Pixels are square, so the footprint is `I_w * GSD / 100` by `I_h * GSD / 100` metres.
///
/// @code
/// adaptseg::CameraModel camera({.image_width_px = 480, .image_height_px = 360});
/// double h = camera.altitude_m(3.0);       // altitude giving 3 cm/px
/// adaptseg::Extent fp = camera.footprint(h); // 14.4 m x 10.8 m
/// @endcode
class CameraModel {
 public:
  using Params = CameraParams;

  /// Largest image a CameraModel accepts [px] (2^28, 268 Mpx): images are materialised in
  /// memory, and width x height must not overflow `int` pixel counts.
  static constexpr long long kMaxImagePixels = 1LL << 28;

  /// @throws std::invalid_argument if a value is not finite and positive, or the image has
  ///         more than kMaxImagePixels pixels.
  explicit CameraModel(Params params = {}) : params_(params) {
    detail::require(params_.image_width_px > 0, "CameraModel: image_width_px must be > 0", params_.image_width_px);
    detail::require(params_.image_height_px > 0, "CameraModel: image_height_px must be > 0", params_.image_height_px);
    detail::require(static_cast<long long>(params_.image_width_px) * params_.image_height_px <= kMaxImagePixels,
                    "CameraModel: the image has too many pixels (image_width_px x image_height_px must be "
                    "<= 2^28)",
                    std::to_string(params_.image_width_px) + "x" + std::to_string(params_.image_height_px));
    detail::require_positive(params_.sensor_width_mm, "CameraModel: sensor_width_mm");
    detail::require_positive(params_.focal_length_mm, "CameraModel: focal_length_mm");
  }

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] int width_px() const noexcept { return params_.image_width_px; }
  [[nodiscard]] int height_px() const noexcept { return params_.image_height_px; }

  /// GSD [cm/px] at altitude `altitude_m` [m].
  /// @throws std::invalid_argument if the altitude is not finite and positive.
  [[nodiscard]] double gsd_cm(double altitude_m) const {
    detail::require_positive(altitude_m, "CameraModel::gsd_cm: altitude_m");
    return 100.0 * altitude_m * params_.sensor_width_mm / (params_.focal_length_mm * params_.image_width_px);
  }

  /// Altitude [m] that gives `gsd_cm` [cm/px]; the inverse of gsd_cm().
  /// @throws std::invalid_argument if the GSD is not finite and positive.
  [[nodiscard]] double altitude_m(double gsd_cm) const {
    detail::require_positive(gsd_cm, "CameraModel::altitude_m: gsd_cm");
    return gsd_cm * params_.focal_length_mm * params_.image_width_px / (100.0 * params_.sensor_width_mm);
  }

  /// Ground footprint at a GSD [cm/px].
  /// @throws std::invalid_argument if the GSD is not finite and positive.
  [[nodiscard]] Extent footprint_at_gsd(double gsd_cm) const {
    detail::require_positive(gsd_cm, "CameraModel::footprint_at_gsd: gsd_cm");
    return {params_.image_width_px * gsd_cm / 100.0, params_.image_height_px * gsd_cm / 100.0};
  }

  /// Ground footprint at an altitude [m].
  /// @throws std::invalid_argument if the altitude is not finite and positive.
  [[nodiscard]] Extent footprint(double altitude_m) const { return footprint_at_gsd(gsd_cm(altitude_m)); }

 private:
  Params params_;
};

}  // namespace adaptseg
