// adaptseg::mavlink's live link: VehicleLink against a fake autopilot in memory, on a fake clock
// (no sleeping): connection, stream requests, acknowledgements and bounded retries, refusals,
// link loss, the site limits, the camera command of each firmware, ArduPilot's GUIDED mode, the
// altitude sent, arrival and a vehicle that stops short; and the transports (UDP on loopback,
// a serial device on a pseudo-terminal, connection strings). The live test against an emulated
// autopilot written with node-mavlink is mavlink:emulator (tests/mavlink/run_link_emulator.sh).

#include <adaptseg/mavlink.hpp>

#include <doctest/doctest.h>

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <system_error>
#include <variant>
#include <vector>

namespace mv = adaptseg::mavlink;
using Bytes = std::vector<std::uint8_t>;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kHomeLat = 25.2;
constexpr double kHomeLon = 55.3;
constexpr double kHomeAmsl = 10.0;

/// A frame the link sent, decoded, and when.
struct Sent {
  mv::Frame frame;
  mv::Message msg;
  double at_s = 0.0;
};

/// An autopilot in memory: answers the link's frames at once, streams HEARTBEAT, GLOBAL_POSITION_INT
/// and GPS_RAW_INT on a clock of its own that advances only while the link waits in receive(), and
/// flies towards its target at `speed_mps`.
struct FakeAutopilot {
  double now = 0.0;
  std::deque<Bytes> inbox;  // frames for the link, in order
  mv::Parser parser;
  std::uint8_t sequence = 0;
  std::int32_t captures = 0;
  std::vector<Sent> sent;  // every frame the link sent

  mv::Heartbeat heartbeat{
      mv::mav_type::kQuadrotor,
      mv::mav_autopilot::kPx4,
      static_cast<std::uint8_t>(mv::mav_mode_flag::kCustomModeEnabled | mv::mav_mode_flag::kSafetyArmed),
      mv::px4_mode::custom_mode(mv::px4_mode::kMainPosctl),
      mv::mav_state::kActive,
      mv::kMavlinkVersion};
  double lat = kHomeLat;
  double lon = kHomeLon;
  double rel_alt = 20.0;
  std::uint16_t heading_cdeg = std::numeric_limits<std::uint16_t>::max();  // GLOBAL_POSITION_INT hdg: unknown
  double speed_mps = 5.0;
  double stop_short_m = 0.0;
  std::optional<mv::LatLonAlt> target;
  std::uint8_t fix_type = mv::gps_fix_type::k3dFix;
  bool heartbeats = true;
  bool positions = true;
  double silent_after_s = kInf;                             // sends and answers nothing from then on
  std::optional<std::pair<double, std::uint32_t>> mode_at;  // the pilot switches the mode at a time
  std::optional<double> disarm_at_s;
  double next_heartbeat_s = 0.0;
  double next_position_s = 0.0;
  double next_gps_s = 0.0;
  double position_period_s = 0.2;  // until SET_MESSAGE_INTERVAL says otherwise
  double gps_period_s = 1.0;
  /// Answers per command, in order (nullopt: no answer); ACCEPTED once they run out.
  std::map<std::uint16_t, std::deque<std::optional<std::uint8_t>>> script;

  [[nodiscard]] bool ardupilot() const { return heartbeat.autopilot == mv::mav_autopilot::kArduPilotMega; }

  template <typename M>
  void emit(const M& msg, std::uint8_t component = mv::mav_component::kAutopilot1) {
    inbox.push_back(mv::encode(msg, {sequence++, 1, component}));
  }

  void ack(std::uint16_t command, std::uint8_t result, const mv::Frame& from) {
    mv::CommandAck a;
    a.command = command;
    a.result = result;
    a.target_system = from.system_id;
    a.target_component = from.component_id;
    emit(a);
  }

  // The link's send().
  void on_bytes(std::span<const std::uint8_t> bytes) {
    parser.feed(bytes);
    while (const auto frame = parser.next()) {
      const mv::Message msg = mv::decode(*frame);
      sent.push_back({*frame, msg, now});
      if (now >= silent_after_s) continue;
      if (const auto* c = std::get_if<mv::CommandLong>(&msg)) {
        on_command(c->command, c->param1, c->param2, 0, 0, c->param7, *frame);
      } else if (const auto* ci = std::get_if<mv::CommandInt>(&msg)) {
        on_command(ci->command, ci->param1, ci->param2, ci->x, ci->y, ci->z, *frame);
      }
    }
  }

  void on_command(std::uint16_t command, float p1, float p2, std::int32_t x, std::int32_t y, float z,
                  const mv::Frame& from) {
    std::optional<std::uint8_t> result = mv::mav_result::kAccepted;
    if (auto it = script.find(command); it != script.end() && !it->second.empty()) {
      result = it->second.front();
      it->second.pop_front();
    }
    if (!result) return;  // lost
    if (*result != mv::mav_result::kAccepted) {
      ack(command, *result, from);
      return;
    }
    switch (command) {
      case mv::mav_cmd::kSetMessageInterval:
        if (static_cast<std::uint32_t>(p1) == mv::GlobalPositionInt::kId) position_period_s = p2 * 1e-6;
        if (static_cast<std::uint32_t>(p1) == mv::GpsRawInt::kId) gps_period_s = p2 * 1e-6;
        break;
      case mv::mav_cmd::kDoSetMode: heartbeat.custom_mode = static_cast<std::uint32_t>(p2); break;
      case mv::mav_cmd::kDoReposition:
        if (ardupilot() && heartbeat.custom_mode != mv::ardupilot_mode::kCopterGuided &&
            (static_cast<int>(p2) & 1) == 0) {
          ack(command, mv::mav_result::kDenied, from);
          return;
        }
        if (!ardupilot()) heartbeat.custom_mode = mv::px4_mode::kHold;
        target = mv::LatLonAlt{x * 1e-7, y * 1e-7, z - kHomeAmsl};  // MAV_FRAME_GLOBAL_INT: above sea level
        break;
      case mv::mav_cmd::kImageStartCapture: {
        mv::CameraImageCaptured img;
        img.lat = static_cast<std::int32_t>(std::lround(lat * 1e7));
        img.lon = static_cast<std::int32_t>(std::lround(lon * 1e7));
        img.image_index = captures++;
        img.capture_result = 1;
        ack(command, mv::mav_result::kAccepted, from);
        emit(img, mv::mav_component::kCamera);
        return;
      }
      case mv::mav_cmd::kNavReturnToLaunch:
        heartbeat.custom_mode = ardupilot()
                                    ? mv::ardupilot_mode::kCopterRtl
                                    : mv::px4_mode::custom_mode(mv::px4_mode::kMainAuto, mv::px4_mode::kAutoRtl);
        target = mv::LatLonAlt{kHomeLat, kHomeLon, rel_alt};
        disarm_at_s = now + 3.0;
        break;
      default: break;
    }
    ack(command, mv::mav_result::kAccepted, from);
  }

  void fly(double dt) {
    if (!target) return;
    const auto d = adaptseg::detail::north_east_m(lat, lon, target->lat_deg, target->lon_deg);
    const double h = std::hypot(d.north_m, d.east_m);
    const double go = std::max(0.0, h - stop_short_m);
    const double step = std::min(go, speed_mps * dt);
    if (h > 0.0 && step > 0.0) {
      const auto p = adaptseg::detail::offset_deg(lat, lon, d.north_m / h * step, d.east_m / h * step);
      lat = p.lat_deg;
      lon = p.lon_deg;
    }
    const double dz = target->rel_alt_m - rel_alt;
    rel_alt += std::clamp(dz, -speed_mps * dt, speed_mps * dt);
  }

  void advance_to(double t) {
    fly(t - now);
    now = t;
    if (mode_at && now >= mode_at->first) {
      heartbeat.custom_mode = mode_at->second;
      mode_at.reset();
    }
    if (disarm_at_s && now >= *disarm_at_s) {
      heartbeat.base_mode = mv::mav_mode_flag::kCustomModeEnabled;
      disarm_at_s.reset();
    }
    if (now >= silent_after_s) return;
    if (heartbeats && now >= next_heartbeat_s) {
      emit(heartbeat);
      next_heartbeat_s += 1.0;
    }
    if (now >= next_gps_s) {
      mv::GpsRawInt g;
      g.fix_type = fix_type;
      g.satellites_visible = fix_type >= 3 ? 12 : 0;
      if (fix_type >= 3) {
        g.lat = static_cast<std::int32_t>(std::lround(lat * 1e7));
        g.lon = static_cast<std::int32_t>(std::lround(lon * 1e7));
      }
      emit(g);
      next_gps_s += gps_period_s;
    }
    if (positions && fix_type >= 3 && now >= next_position_s) {
      mv::GlobalPositionInt p;
      p.lat = static_cast<std::int32_t>(std::lround(lat * 1e7));
      p.lon = static_cast<std::int32_t>(std::lround(lon * 1e7));
      p.relative_alt = static_cast<std::int32_t>(std::lround(rel_alt * 1e3));
      p.alt = static_cast<std::int32_t>(std::lround((rel_alt + kHomeAmsl) * 1e3));
      p.hdg = heading_cdeg;
      emit(p);
      next_position_s += position_period_s;
    }
  }

  // The link's receive(): what is queued, else the clock runs to the next thing to send (or to
  // the end of the wait).
  std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) {
    const double end = now + timeout_s;
    for (;;) {
      if (!inbox.empty()) {
        const Bytes b = std::move(inbox.front());
        inbox.pop_front();
        std::copy(b.begin(), b.end(), buffer.begin());
        return b.size();
      }
      double next = std::min(mode_at ? mode_at->first : kInf, disarm_at_s.value_or(kInf));
      if (now < silent_after_s) {
        next = std::min({next, heartbeats ? next_heartbeat_s : kInf,
                         positions && fix_type >= 3 ? next_position_s : kInf, next_gps_s});
      }
      next = std::max(next, now);
      if (next >= end) {
        advance_to(std::max(now, end));
        if (inbox.empty()) return 0;
        continue;
      }
      advance_to(next);
    }
  }

  /// Frames of type M the link sent.
  template <typename M>
  [[nodiscard]] std::vector<M> sent_of() const {
    std::vector<M> out;
    for (const Sent& s : sent) {
      if (const auto* m = std::get_if<M>(&s.msg)) out.push_back(*m);
    }
    return out;
  }

  /// Commands (long or int) with this id the link sent.
  [[nodiscard]] int commands(std::uint16_t id) const {
    int n = 0;
    for (const auto& c : sent_of<mv::CommandLong>()) n += c.command == id ? 1 : 0;
    for (const auto& c : sent_of<mv::CommandInt>()) n += c.command == id ? 1 : 0;
    return n;
  }
};

/// The link's ByteTransport: a handle to the shared FakeAutopilot.
struct FakeTransport {
  std::shared_ptr<FakeAutopilot> ap;
  void send(std::span<const std::uint8_t> bytes) { ap->on_bytes(bytes); }
  std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) { return ap->receive(buffer, timeout_s); }
  [[nodiscard]] std::string description() const { return "fake"; }
};
static_assert(mv::ByteTransport<FakeTransport>);

/// A 200 m square around home, ceiling 60 m.
mv::SiteLimits site() {
  const auto c = [](double n, double e) {
    const auto p = adaptseg::detail::offset_deg(kHomeLat, kHomeLon, n, e);
    return mv::LatLon{p.lat_deg, p.lon_deg};
  };
  return mv::SiteLimits({c(-100, -100), c(-100, 100), c(100, 100), c(100, -100)}, 60.0);
}

/// A target `north`, `east` metres from home at `alt` above it.
mv::LatLonAlt at(double north, double east, double alt = 20.0) {
  const auto p = adaptseg::detail::offset_deg(kHomeLat, kHomeLon, north, east);
  return {p.lat_deg, p.lon_deg, alt};
}

struct Rig {
  std::shared_ptr<FakeAutopilot> ap = std::make_shared<FakeAutopilot>();
  mv::VehicleLink link;
  explicit Rig(mv::LinkOptions options = {}, std::shared_ptr<FakeAutopilot> autopilot = nullptr)
      : ap(autopilot ? std::move(autopilot) : std::make_shared<FakeAutopilot>()),
        link(FakeTransport{ap}, site(), options, [a = ap.get()] { return a->now; }) {}
};

std::shared_ptr<FakeAutopilot> ardupilot_in_loiter() {
  auto ap = std::make_shared<FakeAutopilot>();
  ap->heartbeat.autopilot = mv::mav_autopilot::kArduPilotMega;
  ap->heartbeat.custom_mode = mv::ardupilot_mode::kCopterLoiter;
  return ap;
}

/// The VehicleLinkError `f()` throws (fails the test if none).
template <typename F>
mv::VehicleLinkError link_error(F&& f) {
  try {
    f();
  } catch (const mv::VehicleLinkError& e) {
    return e;
  }
  FAIL("no VehicleLinkError thrown");
  return mv::VehicleLinkError(mv::LinkFailure::refused, "", "");
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("link: connect learns the autopilot and asks for its position and GPS streams") {
  Rig rig;
  const mv::VehicleInfo& v = rig.link.connect();
  CHECK(v.system_id == 1);
  CHECK(v.component_id == 1);
  CHECK(v.firmware() == mv::Firmware::px4);
  CHECK(mv::to_string(v.firmware()) == "PX4");
  CHECK(mv::to_string(static_cast<mv::Firmware>(7)) == "other");
  CHECK(v.armed());
  CHECK(v.mode() == "Position");
  std::map<std::uint32_t, float> intervals;
  for (const auto& c : rig.ap->sent_of<mv::CommandLong>()) {
    if (c.command == mv::mav_cmd::kSetMessageInterval) intervals[static_cast<std::uint32_t>(c.param1)] = c.param2;
    CHECK(c.target_system == 1);
    CHECK(c.target_component == 1);
  }
  CHECK(intervals.at(mv::GlobalPositionInt::kId) == doctest::Approx(100000.0));
  CHECK(intervals.at(mv::GpsRawInt::kId) == doctest::Approx(500000.0));
  const mv::VehiclePosition& p = rig.link.position();
  CHECK(p.lat_deg == doctest::Approx(kHomeLat));
  CHECK(p.rel_alt_m == doctest::Approx(20.0));
  CHECK(p.home_alt_msl_m() == doctest::Approx(kHomeAmsl));
  CHECK(std::isnan(p.heading_deg));  // hdg UINT16_MAX: unknown
  rig.ap->heading_cdeg = 12345;
  rig.link.poll(rig.link.now() + 0.5);
  CHECK(rig.link.position().heading_deg == doctest::Approx(123.45));
  // Our heartbeat: a ground station's, system 255, component 190.
  const auto hbs = rig.ap->sent_of<mv::Heartbeat>();
  REQUIRE(!hbs.empty());
  CHECK(hbs.front().type == mv::mav_type::kGcs);
  CHECK(hbs.front().autopilot == mv::mav_autopilot::kInvalid);
  CHECK(rig.ap->sent.front().frame.system_id == 255);
  CHECK(rig.ap->sent.front().frame.component_id == 190);
}

TEST_CASE("link: heartbeats go out at 1 Hz while the caller polls") {
  Rig rig;
  rig.link.connect();
  const std::size_t before = rig.ap->sent_of<mv::Heartbeat>().size();
  rig.link.poll(rig.link.now() + 10.0);
  const std::size_t during = rig.ap->sent_of<mv::Heartbeat>().size() - before;
  CHECK(during >= 9);
  CHECK(during <= 11);
}

TEST_CASE("link: connect refuses a vehicle without a 3-D fix") {
  Rig rig(mv::LinkOptions{.fix_timeout_s = 3.0});
  rig.ap->fix_type = mv::gps_fix_type::kNoFix;
  const mv::VehicleLinkError e = link_error([&] { rig.link.connect(); });
  CHECK(e.failure() == mv::LinkFailure::no_gps_fix);
  CHECK(e.step() == "connect");
  CHECK(contains(e.what(), "connect: no 3-D GPS fix within 3.0 s"));
  CHECK(contains(e.what(), "fix_type 1 (no fix), 0 satellites"));
  CHECK(!rig.link.connected());
  CHECK(rig.ap->now == doctest::Approx(3.0).epsilon(0.1));
}

TEST_CASE("link: connect gives up without a heartbeat") {
  Rig rig;
  rig.ap->heartbeats = false;
  const mv::VehicleLinkError e = link_error([&] { rig.link.connect(); });
  CHECK(e.failure() == mv::LinkFailure::no_heartbeat);
  CHECK(contains(e.what(), "connect: no HEARTBEAT from an autopilot within 10.0 s on fake"));
}

TEST_CASE("link: a command without an answer is sent again a bounded number of times") {
  Rig rig(mv::LinkOptions{.ack_timeout_s = 1.5, .command_attempts = 3});
  rig.link.connect();
  rig.ap->script[mv::mav_cmd::kDoReposition] = {std::nullopt, std::nullopt, std::nullopt, std::nullopt};
  const double t0 = rig.link.now();
  const mv::VehicleLinkError e = link_error([&] { rig.link.go_to(at(30, 0)); });
  CHECK(e.failure() == mv::LinkFailure::no_ack);
  CHECK(contains(e.what(), "go_to: no COMMAND_ACK for DO_REPOSITION (192) after 3 attempts, 1.5 s each"));
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 3);
  CHECK(rig.link.now() - t0 == doctest::Approx(4.5).epsilon(0.05));
  CHECK(rig.link.stats().command_retries == 2);
}

TEST_CASE("link: a lost acknowledgement costs one retry of the same command") {
  Rig rig;
  rig.link.connect();
  rig.ap->script[mv::mav_cmd::kDoReposition] = {std::nullopt};
  rig.link.go_to(at(30, 0));
  const auto sent = rig.ap->sent_of<mv::CommandInt>();
  REQUIRE(sent.size() == 2);
  CHECK(mv::encode(sent[0], {}) == mv::encode(sent[1], {}));  // the same command (param4 is NaN)
  CHECK(rig.ap->target.has_value());
  // COMMAND_LONG counts its retransmissions in `confirmation`.
  rig.ap->script[mv::mav_cmd::kImageStartCapture] = {std::nullopt, std::nullopt};
  rig.link.trigger_camera();
  std::vector<int> confirmations;
  for (const auto& c : rig.ap->sent_of<mv::CommandLong>()) {
    if (c.command == mv::mav_cmd::kImageStartCapture) confirmations.push_back(c.confirmation);
  }
  CHECK(confirmations == std::vector<int>{0, 1, 2});
}

TEST_CASE("link: a refused command fails at once and is not sent again") {
  Rig rig;
  rig.link.connect();
  rig.ap->script[mv::mav_cmd::kDoReposition] = {mv::mav_result::kDenied};
  const mv::VehicleLinkError e = link_error([&] { rig.link.go_to(at(30, 0)); });
  CHECK(e.failure() == mv::LinkFailure::refused);
  CHECK(std::string(e.what()) == "go_to: the vehicle refused DO_REPOSITION (192): MAV_RESULT_DENIED");
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 1);
  for (const std::uint8_t r : {mv::mav_result::kFailed, mv::mav_result::kUnsupported}) {
    rig.ap->script[mv::mav_cmd::kNavReturnToLaunch] = {r};
    CHECK(link_error([&] { rig.link.return_to_launch(); }).failure() == mv::LinkFailure::refused);
  }
}

TEST_CASE("link: temporarily rejected is asked again and in progress is waited for") {
  Rig rig;
  rig.link.connect();
  rig.ap->script[mv::mav_cmd::kDoReposition] = {mv::mav_result::kTemporarilyRejected};
  rig.link.go_to(at(30, 0));
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 2);
  rig.ap->script[mv::mav_cmd::kNavReturnToLaunch] = {
      mv::mav_result::kTemporarilyRejected, mv::mav_result::kTemporarilyRejected, mv::mav_result::kTemporarilyRejected,
      mv::mav_result::kTemporarilyRejected};
  const mv::VehicleLinkError e = link_error([&] { rig.link.return_to_launch(); });
  CHECK(e.failure() == mv::LinkFailure::no_ack);
  CHECK(contains(e.what(), "TEMPORARILY_REJECTED, 4 attempts"));
}

TEST_CASE("link: a target outside the site or above the ceiling is never sent") {
  Rig rig;
  rig.link.connect();
  const int before = static_cast<int>(rig.ap->sent.size());
  const mv::VehicleLinkError outside = link_error([&] { rig.link.go_to(at(150, 0)); });
  CHECK(outside.failure() == mv::LinkFailure::outside_site);
  CHECK(contains(outside.what(), "go_to: refused to send the vehicle to ("));
  CHECK(contains(outside.what(), " m): outside the site polygon"));
  const mv::VehicleLinkError high = link_error([&] { rig.link.go_to(at(10, 10, 61.0)); });
  CHECK(high.failure() == mv::LinkFailure::outside_site);
  CHECK(contains(high.what(), "altitude 61.0 m above home is above the ceiling 60.0 m"));
  CHECK(link_error([&] { rig.link.go_to(at(10, 10, -1.0)); }).failure() == mv::LinkFailure::outside_site);
  CHECK(link_error([&] { rig.link.go_to({std::nan(""), kHomeLon, 20.0}); }).failure() == mv::LinkFailure::outside_site);
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 0);
  CHECK(static_cast<int>(rig.ap->sent.size()) == before);  // not even a heartbeat was due
}

TEST_CASE("link: the reposition goes out with the altitude above sea level and PX4's change-mode bit") {
  Rig rig;
  rig.link.connect();
  const mv::LatLonAlt target = at(30, -20, 35.0);
  rig.link.go_to(target);
  const auto sent = rig.ap->sent_of<mv::CommandInt>();
  REQUIRE(sent.size() == 1);
  const mv::CommandInt& c = sent.front();
  CHECK(c.command == mv::mav_cmd::kDoReposition);
  CHECK(c.frame == mv::mav_frame::kGlobalInt);
  CHECK(c.x == std::lround(target.lat_deg * 1e7));
  CHECK(c.y == std::lround(target.lon_deg * 1e7));
  CHECK(c.z == doctest::Approx(kHomeAmsl + 35.0));
  CHECK(c.param1 == -1.0F);
  CHECK(c.param2 == 1.0F);
  CHECK(std::isnan(c.param4));
  CHECK(rig.ap->commands(mv::mav_cmd::kDoSetMode) == 0);
  const mv::Arrival a = rig.link.wait_arrival(target, {.horizontal_m = 0.5, .vertical_m = 0.5});
  CHECK(a.horizontal_m <= 0.5);
  CHECK(std::fabs(a.vertical_m) <= 0.5);
  CHECK(a.waited_s == doctest::Approx(std::hypot(30.0, 20.0) / 5.0).epsilon(0.1));
  CHECK(rig.link.vehicle().mode() == "Hold");
}

TEST_CASE("link: ArduPilot is put in GUIDED once and repositioned without the change-mode bit") {
  Rig rig({}, ardupilot_in_loiter());
  rig.link.connect();
  CHECK(rig.link.vehicle().mode() == "LOITER");
  rig.link.go_to(at(20, 0));
  const auto modes = rig.ap->sent_of<mv::CommandLong>();
  const auto set_mode = std::find_if(modes.begin(), modes.end(),
                                     [](const mv::CommandLong& c) { return c.command == mv::mav_cmd::kDoSetMode; });
  REQUIRE(set_mode != modes.end());
  CHECK(set_mode->param1 == 1.0F);  // MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
  CHECK(set_mode->param2 == 4.0F);  // Copter GUIDED
  CHECK(rig.link.vehicle().mode() == "GUIDED");
  const auto repositions = rig.ap->sent_of<mv::CommandInt>();
  REQUIRE(repositions.size() == 1);
  CHECK(repositions.front().param2 == 0.0F);
  rig.link.wait_arrival(at(20, 0));
  rig.link.go_to(at(20, 20));
  CHECK(rig.ap->commands(mv::mav_cmd::kDoSetMode) == 1);
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 2);
}

TEST_CASE("link: the camera command follows the firmware") {
  Rig px4;
  px4.link.connect();
  const mv::CameraCapture first = px4.link.trigger_camera();
  const mv::CameraCapture second = px4.link.trigger_camera();
  CHECK(first.command == mv::mav_cmd::kImageStartCapture);
  CHECK(first.image.has_value());
  std::vector<float> sequence;
  for (const auto& c : px4.ap->sent_of<mv::CommandLong>()) {
    if (c.command != mv::mav_cmd::kImageStartCapture) continue;
    CHECK(c.param3 == 1.0F);
    sequence.push_back(c.param4);
  }
  CHECK(sequence == std::vector<float>{1.0F, 2.0F});
  CHECK(second.image.has_value());

  Rig ardupilot({.capture_wait_s = 0.5}, ardupilot_in_loiter());
  ardupilot.link.connect();
  const mv::CameraCapture shot = ardupilot.link.trigger_camera();
  CHECK(shot.command == mv::mav_cmd::kDoDigicamControl);
  CHECK(!shot.image.has_value());
  const auto longs = ardupilot.ap->sent_of<mv::CommandLong>();
  CHECK(longs.back().command == mv::mav_cmd::kDoDigicamControl);
  CHECK(longs.back().param5 == 1.0F);
  CHECK(ardupilot.ap->commands(mv::mav_cmd::kImageStartCapture) == 0);
}

TEST_CASE("link: a silent vehicle is a lost link whatever operation runs") {
  Rig rig(mv::LinkOptions{.link_timeout_s = 3.0});
  rig.link.connect();
  rig.link.go_to(at(80, 0));
  const double silent = rig.link.now() + 2.0;
  rig.ap->silent_after_s = silent;
  const mv::VehicleLinkError e = link_error([&] { rig.link.wait_arrival(at(80, 0)); });
  CHECK(e.failure() == mv::LinkFailure::link_lost);
  CHECK(e.step() == "wait_arrival");
  CHECK(contains(e.what(), "wait_arrival: no frame from the vehicle (system 1) for 3.0 s on fake: the link is lost"));
  CHECK(rig.link.now() >= silent + 2.8);
  CHECK(rig.link.now() <= silent + 3.01);
  // LinkLost is the type to catch; every later operation sees the same.
  CHECK_THROWS_AS(rig.link.go_to(at(10, 0)), mv::LinkLost);
  CHECK_THROWS_AS(rig.link.poll(rig.link.now() + 1.0), mv::LinkLost);
}

TEST_CASE("link: a vehicle that stops short fails naming the distance left") {
  Rig rig;
  rig.ap->stop_short_m = 2.0;
  rig.link.connect();
  const mv::LatLonAlt target = at(25, 0);
  rig.link.go_to(target);
  const mv::VehicleLinkError e =
      link_error([&] { rig.link.wait_arrival(target, {.horizontal_m = 0.5, .vertical_m = 0.5, .stall_s = 3.0}); });
  CHECK(e.failure() == mv::LinkFailure::stopped_short);
  CHECK(contains(e.what(), "wait_arrival: the vehicle stopped 2.0 m short of ("));
  CHECK(contains(e.what(), "and made no progress for 3."));
  CHECK(contains(e.what(), " s; tolerance 0.5 m horizontal, 0.5 m vertical"));
  const mv::Arrival a = rig.link.wait_arrival(target, {.horizontal_m = 3.0, .vertical_m = 0.5});
  CHECK(a.horizontal_m == doctest::Approx(2.0).epsilon(0.02));
}

TEST_CASE("link: arrival times out naming the distance left") {
  Rig rig;
  rig.link.connect();
  rig.ap->speed_mps = 0.5;
  rig.link.go_to(at(50, 0));
  const mv::VehicleLinkError e = link_error([&] { rig.link.wait_arrival(at(50, 0), {.timeout_s = 10.0}); });
  CHECK(e.failure() == mv::LinkFailure::arrival_timeout);
  CHECK(contains(e.what(), "wait_arrival: the vehicle did not reach ("));
  CHECK(contains(e.what(), "within 10.0 s (4"));
  CHECK(contains(e.what(), " m left horizontally)"));
}

TEST_CASE("link: a pilot or failsafe taking over stops the link") {
  Rig rig;
  rig.link.connect();
  rig.link.go_to(at(80, 0));
  rig.ap->mode_at = {{rig.link.now() + 5.0, mv::px4_mode::custom_mode(mv::px4_mode::kMainPosctl)}};
  const mv::VehicleLinkError e = link_error([&] { rig.link.wait_arrival(at(80, 0)); });
  CHECK(e.failure() == mv::LinkFailure::mode_changed);
  CHECK(contains(e.what(), "wait_arrival: the vehicle left Hold for Position (the pilot or a failsafe took over)"));
  CHECK(link_error([&] { rig.link.go_to(at(10, 0)); }).failure() == mv::LinkFailure::mode_changed);
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 1);

  Rig returning;
  returning.ap->heartbeat.custom_mode = mv::px4_mode::custom_mode(mv::px4_mode::kMainAuto, mv::px4_mode::kAutoRtl);
  returning.link.connect();
  const mv::VehicleLinkError r = link_error([&] { returning.link.go_to(at(10, 0)); });
  CHECK(r.failure() == mv::LinkFailure::mode_changed);
  CHECK(contains(r.what(), "the vehicle is in Return"));
  CHECK(returning.ap->commands(mv::mav_cmd::kDoReposition) == 0);
}

TEST_CASE("link: a disarmed vehicle is sent nothing") {
  Rig rig;
  rig.ap->heartbeat.base_mode = mv::mav_mode_flag::kCustomModeEnabled;
  rig.link.connect();
  CHECK(!rig.link.vehicle().armed());
  const mv::VehicleLinkError e = link_error([&] { rig.link.go_to(at(10, 0)); });
  CHECK(e.failure() == mv::LinkFailure::not_armed);
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 0);
}

TEST_CASE("link: return to launch is acknowledged and the vehicle lands") {
  Rig rig;
  rig.link.connect();
  rig.link.go_to(at(10, 0));
  rig.link.wait_arrival(at(10, 0));
  rig.link.return_to_launch();
  CHECK(rig.ap->commands(mv::mav_cmd::kNavReturnToLaunch) == 1);
  CHECK(rig.link.wait_disarmed(10.0));
  CHECK(!rig.link.vehicle().armed());
}

TEST_CASE("link: operations before connect are a logic error") {
  Rig rig;
  CHECK_THROWS_AS(rig.link.go_to(at(10, 0)), std::logic_error);
  CHECK_THROWS_AS((void)rig.link.position(), std::logic_error);
  CHECK_THROWS_AS((void)rig.link.vehicle(), std::logic_error);
  CHECK(rig.ap->commands(mv::mav_cmd::kDoReposition) == 0);
}

TEST_CASE("link: bad options, criteria and site limits are refused naming the field") {
  const auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no invalid_argument";
  };
  auto ap = std::make_shared<FakeAutopilot>();
  const auto make = [&](mv::LinkOptions o) { mv::VehicleLink link(FakeTransport{ap}, site(), o); };
  CHECK(contains(message([&] { make({.ack_timeout_s = -1.0}); }), "LinkOptions: ack_timeout_s must be finite and > 0"));
  CHECK(contains(message([&] { make({.command_attempts = 0}); }),
                 "LinkOptions: command_attempts must be 1..100 (got 0)"));
  CHECK(contains(message([&] { make({.system_id = 0}); }), "LinkOptions: system_id must be 1..255"));
  CHECK(contains(message([&] { make({.ground_speed_mps = 0.0}); }), "LinkOptions: ground_speed_mps"));
  CHECK(contains(message([&] { make({.camera_command = 201}); }), "LinkOptions: camera_command must be 0"));
  CHECK(contains(message([] {
                   (void)mv::SiteLimits({{25.2, 55.3}, {25.3, 55.3}}, 100.0);
                 }),
                 "SiteLimits: polygon needs at least 3 vertices (got 2)"));
  CHECK(contains(message([] {
                   (void)mv::SiteLimits({{25.2, 55.3}, {25.3, 55.3}, {95.0, 55.4}}, 100.0);
                 }),
                 "SiteLimits: polygon vertex 2 must be a latitude in -90..90"));
  CHECK(contains(message([] {
                   (void)mv::SiteLimits({{25.2, 55.3}, {25.3, 55.3}, {25.4, 55.3}}, 100.0);
                 }),
                 "SiteLimits: polygon has no area"));
  CHECK(contains(message([] {
                   (void)mv::SiteLimits({{25.2, 55.3}, {25.3, 55.3}, {25.3, 55.4}}, 0.0);
                 }),
                 "SiteLimits: ceiling_m must be finite and above floor_m"));
  Rig rig;
  rig.link.connect();
  CHECK(contains(message([&] { rig.link.wait_arrival(at(10, 0), {.horizontal_m = 0.0}); }),
                 "ArrivalCriteria: horizontal_m must be finite and > 0"));
}

TEST_CASE("site limits: inside and outside a concave polygon") {
  // An L: the notch at north-east is outside.
  const mv::SiteLimits l({{0.0, 0.0}, {0.0, 2.0}, {1.0, 2.0}, {1.0, 1.0}, {2.0, 1.0}, {2.0, 0.0}}, 100.0, 5.0);
  CHECK(l.contains(0.5, 0.5));
  CHECK(l.contains(0.5, 1.5));
  CHECK(l.contains(1.5, 0.5));
  CHECK(!l.contains(1.5, 1.5));
  CHECK(!l.contains(-0.1, 0.5));
  CHECK(!l.violation({0.5, 0.5, 50.0}));
  CHECK(l.violation({0.5, 0.5, 4.0}).value() == "altitude 4.0 m above home is below the floor 5.0 m");
  CHECK(l.violation({1.5, 1.5, 50.0}).value() == "outside the site polygon");
  CHECK(l.violation({std::nan(""), 0.5, 50.0}).value() == "not a finite position");
}

TEST_CASE("firmware modes: PX4 custom modes, ArduPilot GUIDED per vehicle type") {
  CHECK(mv::px4_mode::kHold == 0x03040000u);
  CHECK(mv::mode_name(mv::Firmware::px4, mv::mav_type::kQuadrotor, mv::px4_mode::kHold) == "Hold");
  CHECK(mv::ardupilot_guided_mode(mv::mav_type::kQuadrotor) == 4u);
  CHECK(mv::ardupilot_guided_mode(mv::mav_type::kHexarotor) == 4u);
  CHECK(mv::ardupilot_guided_mode(mv::mav_type::kFixedWing) == 15u);
  CHECK(!mv::ardupilot_guided_mode(mv::mav_type::kGimbal));
  CHECK(mv::is_returning_or_landing(mv::Firmware::ardupilot, mv::mav_type::kQuadrotor, mv::ardupilot_mode::kCopterRtl));
  CHECK(!mv::is_returning_or_landing(mv::Firmware::ardupilot, mv::mav_type::kQuadrotor,
                                     mv::ardupilot_mode::kCopterGuided));
}

TEST_CASE("transport: UDP on loopback learns its peer from the first datagram") {
  mv::UdpTransport gcs = mv::UdpTransport::listen(0, "127.0.0.1");
  const std::uint16_t port = gcs.local_port();
  REQUIRE(port != 0);
  CHECK(gcs.description() == "udpin:127.0.0.1:" + std::to_string(port));
  mv::UdpTransport vehicle = mv::UdpTransport::connect("127.0.0.1", port);
  CHECK(vehicle.has_peer());
  const Bytes hello = mv::encode(mv::Heartbeat{}, {0, 1, 1});
  gcs.send(hello);  // nowhere to go yet
  CHECK(gcs.unsent_frames() == 1);
  CHECK(!gcs.has_peer());
  vehicle.send(hello);
  Bytes buffer(2048);
  CHECK(gcs.receive(buffer, 2.0) == hello.size());
  CHECK(std::equal(hello.begin(), hello.end(), buffer.begin()));
  REQUIRE(gcs.has_peer());
  CHECK(gcs.peer() == "127.0.0.1:" + std::to_string(vehicle.local_port()));
  const Bytes answer = mv::encode(mv::Heartbeat{.type = mv::mav_type::kGcs}, {0, 255, 190});
  gcs.send(answer);
  CHECK(vehicle.receive(buffer, 2.0) == answer.size());
  const double t0 = mv::steady_clock_s();
  CHECK(vehicle.receive(buffer, 0.05) == 0);
  CHECK(mv::steady_clock_s() - t0 >= 0.04);
  // Through the type-erased transport as the link holds it.
  mv::AnyTransport any = std::move(vehicle);
  any.send(hello);
  CHECK(gcs.receive(buffer, 2.0) == hello.size());
  CHECK(any.description() == "udpout:127.0.0.1:" + std::to_string(port));
}

TEST_CASE("transport: a serial device in raw mode on a pseudo-terminal") {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  REQUIRE(master >= 0);
  REQUIRE(::grantpt(master) == 0);
  REQUIRE(::unlockpt(master) == 0);
  const std::string slave = ::ptsname(master);
  {
    mv::SerialTransport serial(slave, 115200);
    CHECK(serial.description() == "serial:" + slave + ":115200");
    const Bytes frame = mv::encode(mv::Heartbeat{}, {3, 1, 1});  // holds 0x0A, 0x0D-like bytes raw mode must keep
    REQUIRE(::write(master, frame.data(), frame.size()) == static_cast<ssize_t>(frame.size()));
    Bytes buffer(512);
    std::size_t got = 0;
    for (int i = 0; i < 20 && got < frame.size(); ++i) {
      got += serial.receive(std::span<std::uint8_t>(buffer).subspan(got), 0.1);
    }
    CHECK(got == frame.size());
    CHECK(std::equal(frame.begin(), frame.end(), buffer.begin()));
    serial.send(frame);
    pollfd p{master, POLLIN, 0};
    REQUIRE(::poll(&p, 1, 1000) == 1);
    Bytes back(512);
    const ssize_t n = ::read(master, back.data(), back.size());
    CHECK(n == static_cast<ssize_t>(frame.size()));
    CHECK(serial.receive(buffer, 0.02) == 0);
  }
  ::close(master);
}

TEST_CASE("transport: connection strings and devices that cannot be opened are refused with one line") {
  const auto message = [](const std::string& spec) -> std::string {
    try {
      (void)mv::open_transport(spec);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "opened";
  };
  CHECK(contains(message("tcp:5760"), "connection 'tcp:5760': unknown scheme 'tcp'; use udpin:[HOST:]PORT"));
  CHECK(contains(message("14550"), "connection '14550': no scheme"));
  CHECK(contains(message("udpin:70000"), "the port must be a number in 0..65535"));
  CHECK(contains(message("udpout:14550"), "udpout needs HOST:PORT"));
  CHECK(contains(message("serial:"), "no device"));
  CHECK(contains(message("serial:/dev/ttyUSB0:12345"), "serial baud rate must be one of 9600"));
  CHECK(contains(message("serial:/no/such/tty:57600"), "serial device /no/such/tty: No such file or directory"));
  CHECK(contains(message("serial:/dev/null"), "serial device /dev/null: tcgetattr"));
  CHECK_THROWS_AS((void)mv::open_transport("serial:/no/such/tty"), std::system_error);
  mv::AnyTransport ok = mv::open_transport("udpin:127.0.0.1:0");
  CHECK(ok.description().rfind("udpin:127.0.0.1:", 0) == 0);
  CHECK(ok.description() != "udpin:127.0.0.1:0");
}
