// The Eigen-only core needs no OpenCV: camera, timing, lawnmower planning.
#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/timing.hpp>

#include <cstdio>

int main() {
  const adaptseg::LawnmowerPlanner planner(adaptseg::CameraModel{});
  const auto plan = planner.plan({0.0, 0.0, 40.0, 30.0}, 3.0);
  std::printf("core consumer: %zu waypoints\n", plan.size());
  return plan.size() == 9 ? 0 : 1;
}
