// A small live loop through adaptseg::mavlink's VehicleLink, for the live test against the
// emulated autopilot (CTest mavlink:emulator, run_link_emulator.sh; emulator.mjs): connect, fly
// a few waypoints around home (go_to, wait_arrival, trigger_camera, "take the image and report
// it to the planner"), return home and wait for the landing.
//
//   adaptseg_mavlink_link_flight --connect SPEC [options]
//
//   --connect SPEC        a connection string (open_transport: udpin:127.0.0.1:0, ...)
//   --port-file FILE      write the local UDP port there once it is bound (for udpin:...:0)
//   --home LAT,LON        home, the centre of the waypoints and of the site (default 25.2,55.3)
//   --waypoints N         waypoints, on a circle around home (default 5)
//   --radius-m R          the circle's radius (default 10)
//   --alt-m A             altitude above home (odd waypoints 5 m higher) (default 20)
//   --tolerance-m T       arrival tolerance, horizontal and vertical (default 0.5)
//   --stall-s S           no progress this long: stopped short (default 3)
//   --site-m S            the site: a square of half-side S around home (default 40)
//   --ceiling-m C         the site's altitude ceiling (default 60)
//   --outside-after K     waypoint K (0-based) lies outside the site instead
//   --link-timeout-s S, --fix-timeout-s S, --ack-timeout-s S, --attempts N, --mode-timeout-s S
//   --land-timeout-s S    wait this long for the landing after RTL (0: do not wait) (default 30)
//
// Exit 0 when it flew every waypoint, returned and landed; 2 with one line on stderr when the
// link failed (VehicleLinkError: what it flew is on stdout); 1 for anything else.

#include <adaptseg/mavlink.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace mv = adaptseg::mavlink;

struct Args {
  std::string connect;
  std::string port_file;
  double home_lat = 25.2;
  double home_lon = 55.3;
  int waypoints = 5;
  double radius_m = 10.0;
  double alt_m = 20.0;
  double tolerance_m = 0.5;
  double stall_s = 3.0;
  double site_m = 40.0;
  double ceiling_m = 60.0;
  int outside_after = -1;
  double land_timeout_s = 30.0;
  mv::LinkOptions link;
};

double number(const std::string& flag, const char* text) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v)) throw std::invalid_argument(flag + " needs a number");
  return v;
}

Args parse(int argc, char** argv) {
  Args a;
  a.link.fix_timeout_s = 5.0;
  a.link.heartbeat_timeout_s = 10.0;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
    const char* value = argv[++i];
    if (flag == "--connect")
      a.connect = value;
    else if (flag == "--port-file")
      a.port_file = value;
    else if (flag == "--home") {
      const std::string s = value;
      const auto comma = s.find(',');
      if (comma == std::string::npos) throw std::invalid_argument("--home needs LAT,LON");
      a.home_lat = number(flag, s.substr(0, comma).c_str());
      a.home_lon = number(flag, s.substr(comma + 1).c_str());
    } else if (flag == "--waypoints")
      a.waypoints = static_cast<int>(number(flag, value));
    else if (flag == "--radius-m")
      a.radius_m = number(flag, value);
    else if (flag == "--alt-m")
      a.alt_m = number(flag, value);
    else if (flag == "--tolerance-m")
      a.tolerance_m = number(flag, value);
    else if (flag == "--stall-s")
      a.stall_s = number(flag, value);
    else if (flag == "--site-m")
      a.site_m = number(flag, value);
    else if (flag == "--ceiling-m")
      a.ceiling_m = number(flag, value);
    else if (flag == "--outside-after")
      a.outside_after = static_cast<int>(number(flag, value));
    else if (flag == "--land-timeout-s")
      a.land_timeout_s = number(flag, value);
    else if (flag == "--link-timeout-s")
      a.link.link_timeout_s = number(flag, value);
    else if (flag == "--fix-timeout-s")
      a.link.fix_timeout_s = number(flag, value);
    else if (flag == "--ack-timeout-s")
      a.link.ack_timeout_s = number(flag, value);
    else if (flag == "--attempts")
      a.link.command_attempts = static_cast<int>(number(flag, value));
    else if (flag == "--mode-timeout-s")
      a.link.mode_timeout_s = number(flag, value);
    else
      throw std::invalid_argument("unknown option " + flag);
  }
  if (a.connect.empty()) throw std::invalid_argument("--connect SPEC is required");
  return a;
}

mv::LatLonAlt offset(const Args& a, double north_m, double east_m, double alt_m) {
  const auto p = adaptseg::detail::offset_deg(a.home_lat, a.home_lon, north_m, east_m);
  return {p.lat_deg, p.lon_deg, alt_m};
}

// Writes the port of "udpin:HOST:PORT" to `file` (through a temporary: the reader sees it whole).
void write_port(const std::string& description, const std::string& file) {
  const std::string port = description.substr(description.rfind(':') + 1);
  {
    std::ofstream out(file + ".tmp");
    out << port << '\n';
  }
  if (std::rename((file + ".tmp").c_str(), file.c_str()) != 0) throw std::runtime_error("cannot write " + file);
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "link_flight: " << e.what() << '\n';
    return 1;
  }
  int flown = 0;
  try {
    mv::AnyTransport transport = mv::open_transport(args.connect);
    if (!args.port_file.empty()) write_port(transport.description(), args.port_file);
    const double s = args.site_m;
    const mv::SiteLimits site({{offset(args, -s, -s, 0).lat_deg, offset(args, -s, -s, 0).lon_deg},
                               {offset(args, -s, s, 0).lat_deg, offset(args, -s, s, 0).lon_deg},
                               {offset(args, s, s, 0).lat_deg, offset(args, s, s, 0).lon_deg},
                               {offset(args, s, -s, 0).lat_deg, offset(args, s, -s, 0).lon_deg}},
                              args.ceiling_m);
    std::vector<mv::LatLonAlt> targets;
    for (int k = 0; k < args.waypoints; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / args.waypoints;
      const double alt = args.alt_m + (k % 2 == 1 ? 5.0 : 0.0);
      targets.push_back(k == args.outside_after
                            ? offset(args, 3.0 * s, 0.0, alt)
                            : offset(args, args.radius_m * std::cos(angle), args.radius_m * std::sin(angle), alt));
    }

    mv::VehicleLink link(std::move(transport), site, args.link);
    const mv::VehicleInfo& v = link.connect();
    std::cout << "connected: " << mv::to_string(v.firmware()) << " system " << int{v.system_id} << ", "
              << (v.armed() ? "armed" : "disarmed") << ", mode " << v.mode() << ", at "
              << mv::to_string(link.position().lat_lon_alt()) << '\n';
    const mv::ArrivalCriteria criteria{
        .horizontal_m = args.tolerance_m, .vertical_m = args.tolerance_m, .timeout_s = 60.0, .stall_s = args.stall_s};
    for (const mv::LatLonAlt& target : targets) {
      link.go_to(target);
      const mv::Arrival arrival = link.wait_arrival(target, criteria);
      const mv::CameraCapture capture = link.trigger_camera();
      ++flown;
      // The live loop takes the image here and reports it to the planner.
      std::cout << "waypoint " << flown << "/" << targets.size() << " " << mv::to_string(target) << ": arrived "
                << adaptseg::detail::fixed_text(arrival.horizontal_m, 2) << " m off after "
                << adaptseg::detail::fixed_text(arrival.waited_s) << " s, " << mv::command_name(capture.command)
                << (capture.image ? ", CAMERA_IMAGE_CAPTURED index " + std::to_string(capture.image->image_index)
                                  : std::string(", no CAMERA_IMAGE_CAPTURED"))
                << '\n';
    }
    link.return_to_launch();
    std::cout << "return to launch acknowledged\n";
    const bool landed = args.land_timeout_s <= 0.0 || link.wait_disarmed(args.land_timeout_s);
    const mv::LinkStats st = link.stats();
    std::cout << "flew " << flown << " of " << targets.size() << " waypoints, returned"
              << (args.land_timeout_s > 0.0 ? (landed ? " and landed" : ", not landed") : "") << "; frames sent "
              << st.frames_sent << ", received " << st.frames_received << ", commands " << st.commands_sent
              << ", retries " << st.command_retries << ", checksum errors " << st.parse.crc_errors << '\n';
    return landed ? 0 : 1;
  } catch (const mv::VehicleLinkError& e) {
    std::cout << "flew " << flown << " of " << args.waypoints << " waypoints; stopped: " << mv::to_string(e.failure())
              << '\n';
    std::cerr << "link_flight: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "link_flight: " << e.what() << '\n';
    return 1;
  }
}
