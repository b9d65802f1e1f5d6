// adaptseg::geo from the installed package: GeographicLib and nlohmann-json found through it.
#include <adaptseg/geo/mission_export.hpp>

#include <cstdio>

int main() {
  const adaptseg::GeoReference geo(adaptseg::FieldGeo{47.4, 8.5, 500.0, 90.0});
  adaptseg::Waypoint w;
  w.position = {100.0, 0.0, 20.0};
  const auto path = adaptseg::make_export_path({w}, geo, "consumer");
  const auto back = adaptseg::read_wpl(adaptseg::write_wpl(path));
  // Take-off, the speed the mission was timed at, the waypoint and its image, return to launch.
  std::printf("geo consumer: %zu items, waypoint at %.7f, %.7f\n", back.items.size(), back.items[2].params[4],
              back.items[2].params[5]);
  return back.items.size() == 5 && back.items[2].params[5] > 8.5 ? 0 : 1;
}
