#include <adaptseg/core/descent_schedule.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

using adaptseg::Area;
using adaptseg::CameraModel;
using adaptseg::LawnmowerPlanner;
using adaptseg::Waypoint;

namespace {
bool overlap(const Area& a, const Area& b) {
  const double eps = 1e-9;
  return a.x_min_m < b.x_max_m - eps && b.x_min_m < a.x_max_m - eps && a.y_min_m < b.y_max_m - eps &&
         b.y_min_m < a.y_max_m - eps;
}
}  // namespace

TEST_CASE("lawnmower: grid size, non-overlapping footprints, full coverage") {
  const LawnmowerPlanner planner(CameraModel{});  // footprint 14.4 x 10.8 m at 3 cm/px
  const Area field{0, 0, 40.0, 30.0};
  const auto plan = planner.plan(field, 3.0);
  REQUIRE(plan.size() == 3 * 3);  // ceil(40/14.4) x ceil(30/10.8)
  for (std::size_t i = 0; i < plan.size(); ++i) {
    CHECK(plan[i].gsd_cm == 3.0);
    CHECK(plan[i].position.z() == doctest::Approx(16.5));
    CHECK(plan[i].footprint.width_m() == doctest::Approx(14.4));
    for (std::size_t j = i + 1; j < plan.size(); ++j) CHECK_FALSE(overlap(plan[i].footprint, plan[j].footprint));
  }
  // Every point of the field lies under some footprint.
  for (double x = 0.05; x < 40.0; x += 0.5)
    for (double y = 0.05; y < 30.0; y += 0.5) {
      bool covered = false;
      for (const auto& w : plan)
        covered |=
            x >= w.footprint.x_min_m && x < w.footprint.x_max_m && y >= w.footprint.y_min_m && y < w.footprint.y_max_m;
      REQUIRE(covered);
    }
}

TEST_CASE("lawnmower: exact multiples give no extra row or column") {
  const LawnmowerPlanner planner(CameraModel{});
  CHECK(planner.plan({0, 0, 14.4 * 4, 10.8 * 2}, 3.0).size() == 8);
}

TEST_CASE("lawnmower: zig-zag order, consecutive waypoints are neighbours") {
  const LawnmowerPlanner planner(CameraModel{});
  const auto plan = planner.plan({0, 0, 50.0, 40.0}, 2.0);  // 9.6 x 7.2 m footprints: 6 x 6
  REQUIRE(plan.size() == 36);
  CHECK(plan.front().footprint.x_min_m == doctest::Approx(0.0));
  CHECK(plan.front().footprint.y_min_m == doctest::Approx(0.0));
  for (std::size_t i = 1; i < plan.size(); ++i) {
    const Eigen::Vector3d d = plan[i].position - plan[i - 1].position;
    const bool step_x = std::abs(std::abs(d.x()) - 9.6) < 1e-9 && std::abs(d.y()) < 1e-9;
    const bool step_y = std::abs(std::abs(d.y()) - 7.2) < 1e-9 && std::abs(d.x()) < 1e-9;
    CHECK((step_x || step_y));
  }
  // Rows alternate direction.
  CHECK(plan[5].position.x() > plan[0].position.x());
  CHECK(plan[11].position.x() < plan[6].position.x());
}

TEST_CASE("lawnmower: sub-lawnmower starts in the corner nearest the UAV and stays on its footprint") {
  const LawnmowerPlanner planner(CameraModel{});
  const auto top = planner.plan({0, 0, 40.0, 30.0}, 3.0);
  const Waypoint& parent = top[4];  // the middle region
  for (const Eigen::Vector2d& uav : {Eigen::Vector2d(100, 100), Eigen::Vector2d(-5, -5), Eigen::Vector2d(100, -5)}) {
    const auto sub = planner.plan(parent.footprint, 1.0, uav);
    REQUIRE(sub.size() == 9);  // 3 x 3 footprints of 4.8 x 3.6 m over 14.4 x 10.8 m
    const Eigen::Vector2d first = sub.front().position.head<2>();
    for (const auto& w : sub) {
      CHECK((w.position.head<2>() - uav).norm() >= (first - uav).norm() - 1e-9);
      CHECK(w.footprint.x_min_m >= parent.footprint.x_min_m - 1e-9);
      CHECK(w.footprint.x_max_m <= parent.footprint.x_max_m + 1e-9);
      CHECK(w.position.z() == doctest::Approx(5.5));
    }
  }
}

TEST_CASE("lawnmower: cells rejected by the predicate are skipped, order kept") {
  const LawnmowerPlanner planner(CameraModel{});
  const Area field{0, 0, 40.0, 30.0};
  const auto all = planner.plan(field, 3.0);
  const auto kept = planner.plan(field, 3.0, {0, 0}, [](const Area& a) { return a.x_min_m < 20.0; });
  REQUIRE(kept.size() == 6);
  std::size_t j = 0;
  for (const auto& w : all)
    if (w.footprint.x_min_m < 20.0) CHECK(kept[j++].position == w.position);
}

TEST_CASE("lawnmower: bad input is rejected") {
  const LawnmowerPlanner planner(CameraModel{});
  CHECK_THROWS_WITH_AS((void)planner.plan({0, 0, 10, 10}, 0.0), doctest::Contains("gsd_cm"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)planner.plan({0, 0, 0, 10}, 1.0), doctest::Contains("area"), std::invalid_argument);
  CHECK_THROWS_AS((void)planner.plan({0, 0, std::nan(""), 10}, 1.0), std::invalid_argument);
}

TEST_CASE("lawnmower: overlap along and across the rows") {
  using adaptseg::LawnmowerOverlap;
  const Area field{0, 0, 40.0, 30.0};  // footprint 14.4 x 10.8 m at 3 cm/px
  // No overlap is the paper's grid, to the bit.
  const auto paper = LawnmowerPlanner(CameraModel{}).plan(field, 3.0, {40.0, 30.0});
  const auto zero = LawnmowerPlanner(CameraModel{}, LawnmowerOverlap{0.0, 0.0}).plan(field, 3.0, {40.0, 30.0});
  REQUIRE(paper.size() == zero.size());
  for (std::size_t i = 0; i < paper.size(); ++i) CHECK(paper[i].footprint == zero[i].footprint);

  for (const Eigen::Vector2d& start : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(40.0, 30.0)}) {
    CAPTURE(start.transpose());
    const LawnmowerPlanner planner(CameraModel{}, LawnmowerOverlap{0.5, 0.25});
    const auto plan = planner.plan(field, 3.0, start);
    // Along: 1 + ceil((40 - 14.4) / 7.2) = 5 columns; across: 1 + ceil((30 - 10.8) / 8.1) = 4 rows.
    REQUIRE(plan.size() == 5 * 4);
    // Neighbours in a row share half a footprint's width; neighbouring rows a quarter of its height.
    CHECK(std::abs(plan[1].footprint.x_min_m - plan[0].footprint.x_min_m) == doctest::Approx(7.2));
    CHECK(std::abs(plan[5].footprint.y_min_m - plan[0].footprint.y_min_m) == doctest::Approx(8.1));
    // The grid is anchored at the start corner; only the far row and column stick out.
    const double x_near = start.x() == 0.0 ? plan[0].footprint.x_min_m : plan[0].footprint.x_max_m;
    const double y_near = start.y() == 0.0 ? plan[0].footprint.y_min_m : plan[0].footprint.y_max_m;
    CHECK(x_near == doctest::Approx(start.x()));
    CHECK(y_near == doctest::Approx(start.y()));
    for (const auto& w : plan) {
      CHECK(w.footprint.width_m() == doctest::Approx(14.4));
      CHECK(w.footprint.height_m() == doctest::Approx(10.8));
    }
    // Every point of the field lies under at least one footprint, and seams are covered twice:
    // a point 0.3 m either side of a paper-grid seam (x = 14.4) is seen by two images.
    int twice = 0;
    for (double x = 0.05; x < 40.0; x += 0.5)
      for (double y = 0.05; y < 30.0; y += 0.5) {
        int seen = 0;
        for (const auto& w : plan)
          seen += x >= w.footprint.x_min_m && x < w.footprint.x_max_m && y >= w.footprint.y_min_m &&
                  y < w.footprint.y_max_m;
        REQUIRE(seen >= 1);
        twice += seen >= 2;
      }
    CHECK(twice > 0);
  }
  // A side no longer than one footprint takes one image whatever the overlap.
  CHECK(LawnmowerPlanner(CameraModel{}, LawnmowerOverlap{0.8, 0.8}).plan(Area{0, 0, 14.4, 10.8}, 3.0).size() == 1);
  CHECK_THROWS_AS(LawnmowerPlanner(CameraModel{}, LawnmowerOverlap{0.95, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(LawnmowerPlanner(CameraModel{}, LawnmowerOverlap{0.0, -0.1}), std::invalid_argument);
  CHECK_THROWS_AS(LawnmowerPlanner(CameraModel{}, LawnmowerOverlap{NAN, 0.0}), std::invalid_argument);
}

TEST_CASE("descent schedules: the windows of a lawnmower, and every name parses back") {
  using adaptseg::descent_schedule_info;
  using adaptseg::DescentSchedule;
  const LawnmowerPlanner planner(CameraModel{});
  const auto plan = planner.plan(Area{0, 0, 40.0, 30.0}, 3.0);  // 3 rows of 3
  REQUIRE(plan.size() == 9);
  using Last = std::vector<std::size_t>;
  CHECK(descent_schedule_info(DescentSchedule::immediate).window_last(plan) == Last{0, 1, 2, 3, 4, 5, 6, 7, 8});
  CHECK(descent_schedule_info(DescentSchedule::tour).window_last(plan) == Last(9, 8));
  CHECK(descent_schedule_info(DescentSchedule::row).window_last(plan) == Last{2, 2, 2, 5, 5, 5, 8, 8, 8});
  CHECK(descent_schedule_info(DescentSchedule::row).window_last({}).empty());
  CHECK_FALSE(descent_schedule_info(DescentSchedule::immediate).defers);
  CHECK(descent_schedule_info(DescentSchedule::tour).defers);
  for (const auto& rule : adaptseg::kDescentSchedules) {
    CHECK(adaptseg::parse_descent_schedule(rule.name) == rule.schedule);
    CHECK(std::string(to_string(rule.schedule)) == rule.name);
  }
  CHECK_THROWS_WITH_AS(static_cast<void>(adaptseg::parse_descent_schedule("later")),
                       "descent schedule must be 'immediate', 'tour' or 'row', not 'later'", std::invalid_argument);
  CHECK_THROWS_AS(static_cast<void>(to_string(static_cast<DescentSchedule>(7))), std::invalid_argument);
}

TEST_CASE("lawnmower: cells_centred_in shares a grid's cells out among regions that tile it, each cell once") {
  // Top level 14.4 x 10.8 m at 3 cm/px, the finer grid 9.6 x 7.2 m at 2 cm/px: 1.5 cells a side.
  for (const adaptseg::LawnmowerOverlap o : {adaptseg::LawnmowerOverlap{}, adaptseg::LawnmowerOverlap{0.2, 0.1}}) {
    CAPTURE(o.along);
    const LawnmowerPlanner planner(CameraModel{}, o);
    const Area laid{0, 0, 40.0, 30.0};
    const auto fine = planner.plan(laid, 2.0);
    std::vector<int> taken(fine.size(), 0);
    std::size_t per_region_min = fine.size(), per_region_max = 0;
    for (const Waypoint& t : LawnmowerPlanner(CameraModel{}).plan(laid, 3.0)) {
      const auto box = planner.cells_centred_in(laid, 2.0, t.footprint, laid);
      REQUIRE(box.has_value());
      // From either corner: the same cells of the laid grid, each centred in the region.
      for (const Eigen::Vector2d& start : {Eigen::Vector2d(box->x_min_m, box->y_min_m), t.position.head<2>().eval()}) {
        const auto cells = planner.plan(*box, 2.0, start);
        for (const Waypoint& c : cells) {
          const Eigen::Vector2d m = c.footprint.centre();
          // In the region, or beyond the field's far edge where the region reaches it.
          const bool far_x = t.footprint.x_max_m >= laid.x_max_m, far_y = t.footprint.y_max_m >= laid.y_max_m;
          CHECK((m.x() >= t.footprint.x_min_m - 1e-9 && (far_x || m.x() < t.footprint.x_max_m) &&
                 m.y() >= t.footprint.y_min_m - 1e-9 && (far_y || m.y() < t.footprint.y_max_m)));
          std::size_t hits = 0;
          for (std::size_t k = 0; k < fine.size(); ++k)
            if ((fine[k].position - c.position).norm() < 1e-9) ++hits, taken[k] += start.x() == box->x_min_m ? 1 : 0;
          CHECK(hits == 1);
        }
        per_region_min = std::min(per_region_min, cells.size());
        per_region_max = std::max(per_region_max, cells.size());
      }
    }
    // Every cell of the finer grid goes to exactly one region; regions get 1 to 4 of them.
    for (int n : taken) CHECK(n == 1);
    CHECK(per_region_min >= 1);
    CHECK(per_region_max <= 4);
  }
  const LawnmowerPlanner planner(CameraModel{});
  // A region beyond the laid grid holds no centre; a grid's own footprint holds exactly itself.
  const Area laid{0, 0, 40.0, 30.0};
  CHECK_FALSE(planner.cells_centred_in(laid, 2.0, {-20.0, 0.0, -10.0, 10.0}, {-20.0, 0.0, 40.0, 30.0}).has_value());
  const auto self = planner.cells_centred_in(laid, 2.0, {9.6, 7.2, 19.2, 14.4}, laid);
  REQUIRE(self.has_value());
  CHECK(self->x_min_m == doctest::Approx(9.6));
  CHECK(self->x_max_m == doctest::Approx(19.2));
  CHECK(planner.plan(*self, 2.0).size() == 1);
  // A region past the field's far edge takes the cells beyond it: the last column's centre (43.2 m) lies
  // on the top level's far edge, outside every region's half-open span.
  const auto last = planner.cells_centred_in(laid, 2.0, {28.8, 0.0, 43.2, 10.8}, laid);
  REQUIRE(last.has_value());
  CHECK(last->x_max_m == doctest::Approx(48.0));
  CHECK_THROWS_AS(static_cast<void>(planner.cells_centred_in(laid, 0.0, {0, 0, 1, 1}, laid)), std::invalid_argument);
  CHECK_THROWS_AS(static_cast<void>(planner.cells_centred_in({0, 0, 0.0, 30.0}, 2.0, {0, 0, 1, 1}, laid)),
                  std::invalid_argument);
}
