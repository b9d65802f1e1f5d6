#pragma once
/// @file
/// Camera presets: the pinhole parameters of a handful of common survey cameras, from their
/// makers' specification sheets (each names its source), besides the library's default. A
/// decision model is calibrated for one camera (CameraParams); a preset gives its sensor width,
/// focal length and full resolution, and the programs' `--camera NAME`. Images are usually
/// segmented at a lower resolution than the sensor's: keep the sensor width and focal length and
/// scale the image size (at_width), which keeps the field of view, so that a camera image
/// resampled to it (examples/common/camera_source.hpp) has the GSD the model expects.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/error.hpp>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>

namespace adaptseg {

/// One camera of the table.
struct CameraPreset {
  std::string_view name;         ///< what `--camera` takes
  std::string_view description;  ///< the camera and its lens
  CameraParams params;           ///< full resolution, sensor width, focal length
  std::string_view source;       ///< where the numbers come from
};

/// The table. Sensor widths are the imager's active width; focal lengths the lens's real one
/// (not the 35 mm equivalent).
inline constexpr std::array<CameraPreset, 5> kCameraPresets{{
    {"default", "the library's default camera (CameraParams{}), which every bundled model is calibrated for",
     CameraParams{480, 360, 4.8, 5.5}, "CameraParams's defaults; no product of its own"},
    {"micasense-rededge-mx", "MicaSense RedEdge-MX, one band (1280 x 960)", CameraParams{1280, 960, 4.8, 5.4},
     "MicaSense RedEdge-MX integration guide and specifications: 1280 x 960 px, 4.8 x 3.6 mm imager, 5.4 mm focal "
     "length"},
    {"dji-phantom4-rtk", "DJI Phantom 4 RTK (FC6310R, 1-inch sensor, 8.8 mm lens; 3:2 photos)",
     CameraParams{5472, 3648, 13.2, 8.8},
     "dji.com/phantom-4-rtk/info (Camera: 1\" CMOS, lens 8.8 mm / 24 mm equivalent, image size 5472 x 3648 at 3:2); "
     "a 1-inch-type sensor is 13.2 x 8.8 mm"},
    {"dji-phantom4-pro", "DJI Phantom 4 Pro / Pro V2.0 (FC6310, 1-inch sensor, 8.8 mm lens; 3:2 photos)",
     CameraParams{5472, 3648, 13.2, 8.8},
     "dji.com/phantom-4-pro-v2/specs (Camera: 1\" CMOS, lens 8.8 mm / 24 mm equivalent, 3:2 image size 5472 x 3648); "
     "a 1-inch-type sensor is 13.2 x 8.8 mm"},
    {"dji-zenmuse-p1-35mm", "DJI Zenmuse P1 with the DJI DL 35mm F2.8 LS ASPH lens (full frame, 3:2 photos)",
     CameraParams{8192, 5460, 35.9, 35.0},
     "dji.com/zenmuse-p1/specs (sensor size 35.9 x 24 mm, photo size 8192 x 5460 at 3:2, DL 35mm lens)"},
}};

/// The preset called `name`.
/// @throws std::invalid_argument naming the presets for an unknown name.
[[nodiscard]] inline const CameraPreset& camera_preset(std::string_view name) {
  for (const auto& p : kCameraPresets)
    if (p.name == name) return p;
  std::string names;
  for (const auto& p : kCameraPresets) names += (names.empty() ? "" : ", ") + std::string(p.name);
  throw std::invalid_argument("unknown camera '" + std::string(name) + "': the presets are " + names);
}

/// `camera` with its image scaled to `width_px` pixels wide (the height rounded to keep the
/// aspect ratio; the sensor width and focal length kept, so the field of view is the same and
/// the GSD at an altitude scales by the camera's width / width_px).
/// @throws std::invalid_argument for a width that is not positive, or as CameraModel.
[[nodiscard]] inline CameraParams at_width(CameraParams camera, int width_px) {
  detail::require(width_px > 0, "at_width: the image width must be > 0 px", width_px);
  const double h = std::round(static_cast<double>(camera.image_height_px) * width_px / camera.image_width_px);
  camera.image_height_px = static_cast<int>(h);
  camera.image_width_px = width_px;
  (void)CameraModel(camera);
  return camera;
}

}  // namespace adaptseg
