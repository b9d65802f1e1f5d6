#pragma once
/// @file
/// Legs kept inside a geofence: a straight leg between two points of a fence (inclusion
/// polygons less exclusion ones, in a plane) that would cross its outline, a concave corner or
/// a hole, flown instead through via points near the fence's corners, the shortest such route
/// (Dijkstra over the visibility graph of the corners' via points). A survey whose waypoints lie
/// inside its site can still breach the site's geofence between two of them; this is what keeps
/// it from doing so. CMake target adaptseg::geo.
///
/// @code
/// const adaptseg::FenceRouter router({l_shaped_ring}, {true}, 1.0);
/// const auto vias = router.route(a, b);  // empty if a -> b is clear; else the corners to pass
/// @endcode

#include <adaptseg/core/error.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <queue>
#include <stdexcept>
#include <utility>
#include <vector>

namespace adaptseg {

/// Shortest routes between points of a planar geofence that keep a clearance from its edges.
///
/// The fence: `rings` [m], ring k an inclusion polygon if `inclusion[k]`, else an exclusion one;
/// a point is inside when it lies in some inclusion ring and in no exclusion ring. A leg a -> b
/// is *clear* when a and b are inside and the segment keeps at least `clearance_m` from every
/// edge (so it crosses none). Via points are placed near every fence corner, on the free side
/// of its angle bisector at 2 and 4 times the clearance (at least 0.5 m), where they are inside
/// and keep the clearance; the shortest route through them is the shortest clear path up to
/// that placement (a shortest path in a polygon bends only at its corners).
class FenceRouter {
 public:
  /// @throws std::invalid_argument for a ring of fewer than 3 vertices, sizes that differ, or
  ///         a clearance that is negative or not finite.
  FenceRouter(std::vector<std::vector<Eigen::Vector2d>> rings, std::vector<bool> inclusion, double clearance_m)
      : rings_(std::move(rings)), inclusion_(std::move(inclusion)), clearance_m_(clearance_m) {
    detail::require(rings_.size() == inclusion_.size(), "FenceRouter: one inclusion flag per ring is needed; flags",
                    inclusion_.size());
    detail::require(std::isfinite(clearance_m) && clearance_m >= 0.0,
                    "FenceRouter: clearance_m must be finite and >= 0", clearance_m);
    for (const auto& r : rings_)
      detail::require(r.size() >= 3, "FenceRouter: a ring needs at least 3 vertices; vertices", r.size());
  }

  [[nodiscard]] double clearance_m() const noexcept { return clearance_m_; }

  /// True if `p` lies in an inclusion ring and in no exclusion ring.
  [[nodiscard]] bool inside(const Eigen::Vector2d& p) const {
    bool included = false;
    for (std::size_t k = 0; k < rings_.size(); ++k) {
      if (!in_ring(rings_[k], p)) continue;
      if (!inclusion_[k]) return false;
      included = true;
    }
    return included;
  }

  /// The least distance [m] from the segment a -> b to any fence edge (0 if it crosses one).
  [[nodiscard]] double distance_to_edges(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& r : rings_)
      for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++)
        best = std::min(best, segment_distance(a, b, r[j], r[i]));
    return best;
  }

  /// True if the straight leg a -> b is inside the fence and keeps the clearance from its edges.
  [[nodiscard]] bool clear(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    if (!inside(a) || !inside(b)) return false;
    const double d = distance_to_edges(a, b);
    return clearance_m_ > 0.0 ? d >= clearance_m_ : d > 0.0;
  }

  /// The via points (a and b excluded) of the shortest clear route from a to b: empty when the
  /// straight leg is clear.
  /// @throws std::invalid_argument if a or b lies outside the fence, or no clear route joins them.
  [[nodiscard]] std::vector<Eigen::Vector2d> route(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    if (clear(a, b)) return {};
    if (!inside(a) || !inside(b))
      throw std::invalid_argument("FenceRouter::route: the leg's " + std::string(inside(a) ? "end" : "start") +
                                  " lies outside the geofence");
    build_graph();
    const std::size_t n = vias_.size(), start = n, goal = n + 1;
    // Dijkstra over the vias, a (start) and b (goal).
    std::vector<double> dist(n + 2, std::numeric_limits<double>::infinity());
    std::vector<std::size_t> prev(n + 2, n + 2);
    const auto point = [&](std::size_t i) -> const Eigen::Vector2d& {
      return i == start ? a : i == goal ? b : vias_[i];
    };
    using Item = std::pair<double, std::size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    dist[start] = 0.0;
    queue.emplace(0.0, start);
    std::vector<char> to_goal(n, 0);
    for (std::size_t i = 0; i < n; ++i) to_goal[i] = clear(vias_[i], b) ? 1 : 0;
    while (!queue.empty()) {
      // Named copies, not a structured binding: a lambda below captures them, which Clang
      // accepts only from version 16.
      const double d = queue.top().first;
      const std::size_t i = queue.top().second;
      queue.pop();
      if (d > dist[i]) continue;
      if (i == goal) break;
      const auto relax = [&](std::size_t j) {
        const double nd = d + (point(j) - point(i)).norm();
        if (nd < dist[j]) {
          dist[j] = nd, prev[j] = i;
          queue.emplace(nd, j);
        }
      };
      if (i == start) {
        for (std::size_t j = 0; j < n; ++j)
          if (clear(a, vias_[j])) relax(j);
      } else {
        for (std::size_t j : visible_[i]) relax(j);
        if (to_goal[i]) relax(goal);
      }
    }
    if (!std::isfinite(dist[goal]))
      throw std::invalid_argument("FenceRouter::route: no route inside the geofence keeps " +
                                  std::to_string(clearance_m_) + " m from its edges between the leg's ends");
    std::vector<Eigen::Vector2d> out;
    for (std::size_t i = prev[goal]; i != start; i = prev[i]) out.push_back(vias_[i]);
    std::reverse(out.begin(), out.end());
    return out;
  }

 private:
  static bool in_ring(const std::vector<Eigen::Vector2d>& r, const Eigen::Vector2d& p) {
    bool in = false;
    for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++)
      if ((r[i].y() > p.y()) != (r[j].y() > p.y()) &&
          p.x() < (r[j].x() - r[i].x()) * (p.y() - r[i].y()) / (r[j].y() - r[i].y()) + r[i].x())
        in = !in;
    return in;
  }

  static double point_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + t * ab - p).norm();
  }

  static double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

  /// Distance between segments ab and cd: 0 if they intersect, else the least endpoint-to-segment distance.
  static double segment_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                                 const Eigen::Vector2d& d) {
    const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a), d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
    if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0) return 0.0;
    return std::min({point_segment(a, c, d), point_segment(b, c, d), point_segment(c, a, b), point_segment(d, a, b)});
  }

  /// The via points near every corner and which of them see each other; once.
  void build_graph() const {
    if (built_) return;
    built_ = true;
    const double step = std::max(clearance_m_, 0.5);
    for (const auto& r : rings_)
      for (std::size_t i = 0; i < r.size(); ++i) {
        const Eigen::Vector2d& v = r[i];
        const Eigen::Vector2d u = (r[(i + r.size() - 1) % r.size()] - v).normalized(),
                              w = (r[(i + 1) % r.size()] - v).normalized();
        Eigen::Vector2d bisector = u + w;
        if (bisector.norm() < 1e-9) bisector = Eigen::Vector2d(-u.y(), u.x());  // a straight corner: its normal
        bisector.normalize();
        for (double side : {1.0, -1.0})
          for (double s : {2.0, 4.0}) {
            const Eigen::Vector2d p = v + side * s * step * bisector;
            if (inside(p) && distance_to_edges(p, p) >= clearance_m_) vias_.push_back(p);
          }
      }
    visible_.assign(vias_.size(), {});
    for (std::size_t i = 0; i < vias_.size(); ++i)
      for (std::size_t j = i + 1; j < vias_.size(); ++j)
        if (clear(vias_[i], vias_[j])) visible_[i].push_back(j), visible_[j].push_back(i);
  }

  std::vector<std::vector<Eigen::Vector2d>> rings_;
  std::vector<bool> inclusion_;
  double clearance_m_;
  mutable bool built_ = false;
  mutable std::vector<Eigen::Vector2d> vias_;
  mutable std::vector<std::vector<std::size_t>> visible_;
};

}  // namespace adaptseg
