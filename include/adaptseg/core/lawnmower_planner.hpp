#pragma once
/// @file
/// Zig-zag (boustrophedon) coverage with non-overlapping camera footprints (paper §3.2.1;
/// docs/method.md, "Decisions where the paper is silent, and departures"): the top-level plan
/// `W^{h_max}` and the sub-lawnmower `W^{h'}` that re-maps
/// one top-level footprint at a lower altitude.

#include <adaptseg/core/area.hpp>
#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/error.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// A place to stop, take an image and decide (paper §3.2.1: zero velocity there).
struct Waypoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< x, y [m] field frame; z altitude [m]
  double gsd_cm = 0.0;                                 ///< GSD of the image taken here [cm/px]
  Area footprint;                                      ///< ground seen from here [m]
};

/// Image overlap of a lawnmower (beyond the paper, whose footprints tile the area without
/// overlap: the default). `along`: the fraction of a footprint's width shared with the next
/// image of its row (rows run along x); `across`: the fraction of its height shared with the
/// neighbouring row. Photogrammetry surveys fly 0.6-0.8; a little overlap closes the seams that
/// position errors open between footprints that only touch.
struct LawnmowerOverlap {
  double along = 0.0;   ///< in [0, 0.9]
  double across = 0.0;  ///< in [0, 0.9]

  friend bool operator==(const LawnmowerOverlap&, const LawnmowerOverlap&) = default;
};

/// Lawnmower coverage of a rectangle at one altitude: the rectangle is cut into a grid of
/// camera footprints (ceil(width / footprint width) by ceil(height / footprint height)),
/// anchored at the starting corner so that only the far row and column may stick out, and
/// visited row by row, alternating direction. Cells for which `keep(footprint)` is false
/// (e.g. no valid field pixel under them) are skipped without changing the order of the rest.
/// With an overlap o the grid steps by (1 - o) footprints and has 1 + ceil((L - f) / ((1 - o) f))
/// cells along a side of length L > f (f: the footprint's side); o = 0 is the grid above.
///
/// @code
/// adaptseg::LawnmowerPlanner planner(adaptseg::CameraModel{});
/// adaptseg::Area field{0, 0, 40, 30};
/// auto top = planner.plan(field, 3.0);                           // W^{h_max}
/// auto sub = planner.plan(top[0].footprint, 1.0, top[0].position.head<2>());  // W^{h'}
/// @endcode
class LawnmowerPlanner {
 public:
  /// @throws std::invalid_argument via CameraModel for an invalid camera, and for an overlap
  ///         outside [0, 0.9].
  explicit LawnmowerPlanner(CameraModel camera, LawnmowerOverlap overlap = {}) : camera_(camera), overlap_(overlap) {
    detail::require(std::isfinite(overlap.along) && overlap.along >= 0.0 && overlap.along <= 0.9,
                    "LawnmowerPlanner: overlap.along must be in [0, 0.9]", overlap.along);
    detail::require(std::isfinite(overlap.across) && overlap.across >= 0.0 && overlap.across <= 0.9,
                    "LawnmowerPlanner: overlap.across must be in [0, 0.9]", overlap.across);
  }

  [[nodiscard]] const CameraModel& camera() const noexcept { return camera_; }
  [[nodiscard]] const LawnmowerOverlap& overlap() const noexcept { return overlap_; }

  /// Covers `area` at `gsd_cm`, starting in the corner of `area` nearest `start_xy` [m].
  /// @throws std::invalid_argument if the GSD is not positive or the area is empty.
  template <typename Keep>
  [[nodiscard]] std::vector<Waypoint> plan(const Area& area, double gsd_cm, const Eigen::Vector2d& start_xy,
                                           Keep&& keep) const {
    detail::require_positive(gsd_cm, "LawnmowerPlanner::plan: gsd_cm");
    require_extent(area, "LawnmowerPlanner::plan: area must have a finite positive size [m]");
    const Extent fp = camera_.footprint_at_gsd(gsd_cm);
    const double altitude = camera_.altitude_m(gsd_cm);
    const double step_x = fp.width_m * (1.0 - overlap_.along);
    const double step_y = fp.height_m * (1.0 - overlap_.across);
    const int nx = cells(area.width_m(), fp.width_m, overlap_.along);
    const int ny = cells(area.height_m(), fp.height_m, overlap_.across);
    // Start corner: the side of each axis nearest the UAV; the grid grows away from it.
    const bool from_x_min = std::abs(start_xy.x() - area.x_min_m) <= std::abs(start_xy.x() - area.x_max_m);
    const bool from_y_min = std::abs(start_xy.y() - area.y_min_m) <= std::abs(start_xy.y() - area.y_max_m);

    std::vector<Waypoint> out;
    out.reserve(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
    for (int row = 0; row < ny; ++row) {
      const double y0 = from_y_min ? area.y_min_m + row * step_y : far_edge(area.y_max_m, row, step_y, fp.height_m);
      for (int k = 0; k < nx; ++k) {
        const int col = (row % 2 == 0) ? k : nx - 1 - k;
        const double x0 = from_x_min ? area.x_min_m + col * step_x : far_edge(area.x_max_m, col, step_x, fp.width_m);
        Waypoint w;
        w.footprint = {x0, y0, x0 + fp.width_m, y0 + fp.height_m};
        const Eigen::Vector2d c = w.footprint.centre();
        w.position = {c.x(), c.y(), altitude};
        w.gsd_cm = gsd_cm;
        if (keep(w.footprint)) out.push_back(w);
      }
    }
    return out;
  }

  /// The rectangle the grid of plan() at `gsd_cm` fills when it is laid *centred* on `area`: its
  /// whole footprints' extent, the overhang split evenly between opposite sides (plan() over it
  /// covers `area` with every footprint's centre inside `area`; plan() over `area` itself leaves
  /// the whole overhang on the far side, the paper's grid).
  /// @throws std::invalid_argument if the GSD is not positive or the area is empty.
  [[nodiscard]] Area centred_grid(const Area& area, double gsd_cm) const {
    detail::require_positive(gsd_cm, "LawnmowerPlanner::centred_grid: gsd_cm");
    require_extent(area, "LawnmowerPlanner::centred_grid: area must have a finite positive size [m]");
    const Extent fp = camera_.footprint_at_gsd(gsd_cm);
    const int nx = cells(area.width_m(), fp.width_m, overlap_.along);
    const int ny = cells(area.height_m(), fp.height_m, overlap_.across);
    const double w = (nx - 1) * fp.width_m * (1.0 - overlap_.along) + fp.width_m;
    const double h = (ny - 1) * fp.height_m * (1.0 - overlap_.across) + fp.height_m;
    const double dx = 0.5 * (w - area.width_m()), dy = 0.5 * (h - area.height_m());
    return {area.x_min_m - dx, area.y_min_m - dy, area.x_max_m + dx, area.y_max_m + dy};
  }

  /// The cells of the grid that plan() lays on `laid` at `gsd_cm` from its corner (x_min, y_min)
  /// whose centres lie in `region` (x_min <= c < x_max on each axis, within 1e-9 of a step; where
  /// `region` reaches an edge of `bounds`, the rectangle the regions were laid to cover, beyond
  /// that edge too): the rectangle of their whole footprints, or nothing where no centre does.
  /// plan() over it, from any corner, flies exactly those cells of the laid grid, so regions that
  /// tile `bounds` (a lawnmower's footprints over it) share out its cells, each to one region
  /// (AdaptiveOptions::descent_grid, DescentGrid::field).
  /// @throws std::invalid_argument as plan().
  [[nodiscard]] std::optional<Area> cells_centred_in(const Area& laid, double gsd_cm, const Area& region,
                                                     const Area& bounds) const {
    detail::require_positive(gsd_cm, "LawnmowerPlanner::cells_centred_in: gsd_cm");
    require_extent(laid, "LawnmowerPlanner::cells_centred_in: laid must have a finite positive size [m]");
    const Extent fp = camera_.footprint_at_gsd(gsd_cm);
    // Per axis the first and last cell index whose centre lies in [lo, hi) (open where the
    // region reaches the bounds' edge).
    const auto span = [](double origin, double f, double step, int n, double lo, double hi, double b_lo, double b_hi) {
      const double tol = 1e-9 * step;
      const int first =
          lo <= b_lo + tol ? 0 : std::max(0, static_cast<int>(std::ceil((lo - origin - 0.5 * f) / step - 1e-9)));
      const int last = hi >= b_hi - tol
                           ? n - 1
                           : std::min(n - 1, static_cast<int>(std::ceil((hi - origin - 0.5 * f) / step - 1e-9)) - 1);
      return std::pair{first, last};
    };
    const double sx = fp.width_m * (1.0 - overlap_.along), sy = fp.height_m * (1.0 - overlap_.across);
    const auto [x0, x1] = span(laid.x_min_m, fp.width_m, sx, cells(laid.width_m(), fp.width_m, overlap_.along),
                               region.x_min_m, region.x_max_m, bounds.x_min_m, bounds.x_max_m);
    const auto [y0, y1] = span(laid.y_min_m, fp.height_m, sy, cells(laid.height_m(), fp.height_m, overlap_.across),
                               region.y_min_m, region.y_max_m, bounds.y_min_m, bounds.y_max_m);
    if (x0 > x1 || y0 > y1) return std::nullopt;
    return Area{laid.x_min_m + x0 * sx, laid.y_min_m + y0 * sy, laid.x_min_m + x1 * sx + fp.width_m,
                laid.y_min_m + y1 * sy + fp.height_m};
  }

  /// plan() keeping every cell.
  [[nodiscard]] std::vector<Waypoint> plan(const Area& area, double gsd_cm, const Eigen::Vector2d& start_xy) const {
    return plan(area, gsd_cm, start_xy, [](const Area&) { return true; });
  }

  /// plan() from the corner (x_min, y_min), keeping every cell.
  [[nodiscard]] std::vector<Waypoint> plan(const Area& area, double gsd_cm) const {
    return plan(area, gsd_cm, Eigen::Vector2d(area.x_min_m, area.y_min_m));
  }

 private:
  /// Refuses, with `what`, a rectangle without a finite positive width and height.
  static void require_extent(const Area& a, const char* what) {
    detail::require(
        std::isfinite(a.width_m()) && a.width_m() > 0.0 && std::isfinite(a.height_m()) && a.height_m() > 0.0, what,
        a.width_m() * a.height_m());
  }

  /// Number of footprints needed along one axis; a tolerance keeps exact multiples exact.
  static int cells(double length_m, double footprint_m, double overlap) {
    if (overlap == 0.0) return std::max(1, static_cast<int>(std::ceil(length_m / footprint_m - 1e-9)));
    if (length_m <= footprint_m * (1.0 + 1e-9)) return 1;
    return 1 + static_cast<int>(std::ceil((length_m - footprint_m) / (footprint_m * (1.0 - overlap)) - 1e-9));
  }

  /// Low edge of cell `i` counted from the high edge `max` of a side; without overlap exactly
  /// the paper's max - (i + 1) f (the same floating-point value as before overlaps existed).
  static double far_edge(double max, int i, double step, double footprint) {
    return step == footprint ? max - (i + 1) * footprint : max - i * step - footprint;
  }

  CameraModel camera_;
  LawnmowerOverlap overlap_;
};

}  // namespace adaptseg
