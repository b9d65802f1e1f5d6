#pragma once
/// @file
/// The field frame's rectangles (Area): a field's extent, a camera footprint, a survey area.
/// Its own header so that code that only places rasters or footprints (image.hpp) need not
/// include the planners.

#include <Eigen/Core>

namespace adaptseg {

/// Axis-aligned rectangle in the field frame [m] (x east along the orthomosaic's columns,
/// y north up its rows, origin at the orthomosaic's bottom-left corner).
struct Area {
  double x_min_m = 0.0;
  double y_min_m = 0.0;
  double x_max_m = 0.0;
  double y_max_m = 0.0;

  [[nodiscard]] double width_m() const noexcept { return x_max_m - x_min_m; }
  [[nodiscard]] double height_m() const noexcept { return y_max_m - y_min_m; }
  [[nodiscard]] Eigen::Vector2d centre() const noexcept {
    return {0.5 * (x_min_m + x_max_m), 0.5 * (y_min_m + y_max_m)};
  }
  friend bool operator==(const Area&, const Area&) = default;
};

}  // namespace adaptseg
