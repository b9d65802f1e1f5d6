// adaptseg::mavlink: the checksum, the field lists against the published CRC_EXTRA values, every
// message through encode, the parser and decode, byte-for-byte against frames node-mavlink
// encoded (tests/data/mavlink/node_frames.txt, written by tests/mavlink/make_frames.mjs), and
// the parser on cut, corrupted, garbage-laden, split and over-long input. The live cross-check
// with node-mavlink is mavlink:node_peer (tests/mavlink/run_node_peer.sh).

#include "mavlink/frame_lines.hpp"

#include <adaptseg/mavlink.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace mv = adaptseg::mavlink;
namespace t = adaptseg::mavlink::test;
using Bytes = std::vector<std::uint8_t>;

namespace {

const std::vector<t::FrameLine>& node_frames() {
  static const std::vector<t::FrameLine> lines = t::read_lines(ADAPTSEG_TEST_DATA_DIR "/mavlink/node_frames.txt");
  return lines;
}

/// The first line of the fixture with this message name (and, if given, payload length).
const t::FrameLine& node_frame(const std::string& name, int payload_length = -1) {
  for (const auto& l : node_frames()) {
    if (l.name == name && (payload_length < 0 || l.bytes[1] == payload_length)) return l;
  }
  throw std::runtime_error("no " + name + " in node_frames.txt");
}

/// Frames the parser yields for `bytes` fed in one chunk.
std::vector<mv::Frame> parse(mv::Parser& parser, std::span<const std::uint8_t> bytes) {
  parser.feed(bytes);
  std::vector<mv::Frame> out;
  while (auto f = parser.next()) out.push_back(*f);
  return out;
}

std::vector<mv::Frame> parse(std::span<const std::uint8_t> bytes) {
  mv::Parser parser;
  return parse(parser, bytes);
}

/// Bytes a frame took on the wire.
std::size_t wire_size(const mv::Frame& f) {
  return (f.version == mv::ProtocolVersion::v2 ? mv::kHeaderLengthV2 : mv::kHeaderLengthV1) + f.payload_length +
         mv::kChecksumLength + (f.signature ? mv::kSignatureLength : 0);
}

/// Every byte fed is in an accepted frame, a skipped one, dropped, or pending.
void check_accounting(const mv::Parser& parser, const std::vector<mv::Frame>& frames) {
  std::uint64_t in_frames = 0;
  for (const auto& f : frames) in_frames += wire_size(f);
  const mv::ParseStats& s = parser.stats();
  CHECK(s.frames_ok == frames.size());
  CHECK(s.bytes_fed == in_frames + s.skipped_bytes + s.dropped_bytes + parser.pending());
}

/// Same message, floats bit for bit (NaN equals NaN).
bool same_message(const mv::Message& a, const mv::Message& b) {
  return a.index() == b.index() && mv::encode(a, {}) == mv::encode(b, {});
}

/// A MAVLink 2 frame of message id `id` with exactly `payload` (no truncation), checksum right
/// for `crc_extra`.
Bytes raw_frame(std::uint32_t id, const Bytes& payload, std::uint8_t crc_extra, std::uint8_t incompat = 0) {
  Bytes out(mv::kHeaderLengthV2 + payload.size());
  const std::array<std::uint8_t, mv::kHeaderLengthV2> header = {mv::kStartV2,
                                                                static_cast<std::uint8_t>(payload.size()),
                                                                incompat,
                                                                0,
                                                                9,
                                                                1,
                                                                1,
                                                                static_cast<std::uint8_t>(id & 0xFF),
                                                                static_cast<std::uint8_t>((id >> 8) & 0xFF),
                                                                static_cast<std::uint8_t>(id >> 16)};
  std::copy(header.begin(), header.end(), out.begin());
  std::copy(payload.begin(), payload.end(), out.begin() + static_cast<std::ptrdiff_t>(mv::kHeaderLengthV2));
  std::uint16_t crc = mv::crc_calculate(std::span<const std::uint8_t>(out.data() + 1, out.size() - 1));
  crc = mv::crc_accumulate(crc_extra, crc);
  out.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  out.push_back(static_cast<std::uint8_t>(crc >> 8));
  return out;
}

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

const mv::Heartbeat kPx4Heartbeat{.type = mv::mav_type::kQuadrotor,
                                  .autopilot = mv::mav_autopilot::kPx4,
                                  .base_mode = 157,
                                  .custom_mode = 0x04040000,
                                  .system_status = mv::mav_state::kActive};

}  // namespace

// A definition with its fields out of wire order, one with a wrong CRC_EXTRA, one without a
// field list: none is a MessageType. (Named namespace: clang warns of unused == otherwise.)
namespace mavlink_concept_checks {
struct OutOfOrder {
  static constexpr std::uint32_t kId = 46;
  static constexpr std::string_view kName = "MISSION_ITEM_REACHED";
  static constexpr std::uint8_t kCrcExtra = 11;
  std::uint8_t a = 0;
  std::uint16_t seq = 0;
  friend bool operator==(const OutOfOrder&, const OutOfOrder&) = default;
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("a", &OutOfOrder::a);
    v.field("seq", &OutOfOrder::seq);
  }
};
struct WrongCrcExtra {
  static constexpr std::uint32_t kId = 46;
  static constexpr std::string_view kName = "MISSION_ITEM_REACHED";
  static constexpr std::uint8_t kCrcExtra = 12;
  std::uint16_t seq = 0;
  friend bool operator==(const WrongCrcExtra&, const WrongCrcExtra&) = default;
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("seq", &WrongCrcExtra::seq);
  }
};
struct SignedWhereUnsigned {  // seq as int16_t: another type, another CRC_EXTRA
  static constexpr std::uint32_t kId = 46;
  static constexpr std::string_view kName = "MISSION_ITEM_REACHED";
  static constexpr std::uint8_t kCrcExtra = 11;
  std::int16_t seq = 0;
  friend bool operator==(const SignedWhereUnsigned&, const SignedWhereUnsigned&) = default;
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("seq", &SignedWhereUnsigned::seq);
  }
};
struct NoFieldList {
  static constexpr std::uint32_t kId = 46;
  static constexpr std::string_view kName = "MISSION_ITEM_REACHED";
  static constexpr std::uint8_t kCrcExtra = 11;
  std::uint16_t seq = 0;
  friend bool operator==(const NoFieldList&, const NoFieldList&) = default;
};
struct RightCopy {  // the published definition: a MessageType
  static constexpr std::uint32_t kId = 46;
  static constexpr std::string_view kName = "MISSION_ITEM_REACHED";
  static constexpr std::uint8_t kCrcExtra = 11;
  std::uint16_t seq = 0;
  friend bool operator==(const RightCopy&, const RightCopy&) = default;
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("seq", &RightCopy::seq);
  }
};
static_assert(mv::MessageType<RightCopy>);
static_assert(!mv::MessageType<OutOfOrder>);
static_assert(!mv::MessageType<WrongCrcExtra>);
static_assert(!mv::MessageType<SignedWhereUnsigned>);
static_assert(!mv::MessageType<NoFieldList>);
static_assert(!mv::MessageType<int>);
static_assert(!mv::MessageType<mv::Message>);
}  // namespace mavlink_concept_checks

TEST_CASE("mavlink: CRC-16/MCRF4XX of known vectors") {
  const std::string digits = "123456789";
  CHECK(mv::crc_calculate(std::string_view(digits)) == 0x6F91);  // the catalogue's check value
  CHECK(mv::crc_calculate(std::span<const std::uint8_t>()) == 0xFFFF);
  CHECK(mv::crc_accumulate(0x00, 0xFFFF) == 0x0F87);
  std::uint16_t crc = mv::kCrcInit;
  for (const char c : digits) crc = mv::crc_accumulate(static_cast<std::uint8_t>(c), crc);
  CHECK(crc == 0x6F91);
  static_assert(mv::crc_calculate(std::string_view("123456789")) == 0x6F91);
  // The checksum of a frame node-mavlink wrote: header and payload, then HEARTBEAT's CRC_EXTRA.
  const Bytes& hb = node_frame("HEARTBEAT").bytes;
  std::uint16_t frame_crc = mv::crc_calculate(std::span<const std::uint8_t>(hb.data() + 1, hb.size() - 3));
  frame_crc = mv::crc_accumulate(50, frame_crc);
  CHECK(frame_crc == (hb[hb.size() - 2] | (hb[hb.size() - 1] << 8)));
}

TEST_CASE("mavlink: CRC_EXTRA and lengths from the field lists equal the published ones") {
  // CRC_EXTRA and payload lengths (without / with extensions) as common.xml's generated
  // headers give them; MessageType already requires the computed CRC_EXTRA to equal kCrcExtra.
  struct Published {
    std::uint32_t id;
    const char* name;
    int crc_extra, base_length, full_length;
  };
  const std::vector<Published> published = {
      {0, "HEARTBEAT", 50, 9, 9},
      {1, "SYS_STATUS", 124, 31, 43},
      {24, "GPS_RAW_INT", 24, 30, 52},
      {33, "GLOBAL_POSITION_INT", 104, 28, 28},
      {42, "MISSION_CURRENT", 28, 2, 18},
      {46, "MISSION_ITEM_REACHED", 11, 2, 2},
      {75, "COMMAND_INT", 158, 35, 35},
      {76, "COMMAND_LONG", 152, 33, 33},
      {77, "COMMAND_ACK", 143, 3, 10},
      {86, "SET_POSITION_TARGET_GLOBAL_INT", 5, 53, 53},
      {87, "POSITION_TARGET_GLOBAL_INT", 150, 51, 51},
      {242, "HOME_POSITION", 104, 52, 60},
      {245, "EXTENDED_SYS_STATE", 130, 2, 2},
      {253, "STATUSTEXT", 83, 51, 54},
      {263, "CAMERA_IMAGE_CAPTURED", 133, 255, 255},
  };
  REQUIRE(published.size() == std::variant_size_v<mv::Message>);
  for (const auto& p : published) {
    CAPTURE(p.name);
    const mv::MessageInfo* info = mv::find_message_info(p.id);
    REQUIRE(info != nullptr);
    CHECK(info->name == p.name);
    CHECK(info->crc_extra == p.crc_extra);
    CHECK(info->base_length == static_cast<std::size_t>(p.base_length));
    CHECK(info->full_length == static_cast<std::size_t>(p.full_length));
  }
  CHECK(mv::crc_extra_of<mv::Heartbeat>() == 50);
  CHECK(mv::crc_extra_of<mv::CameraImageCaptured>() == 133);
  CHECK(mv::find_message_info(30) == nullptr);  // ATTITUDE: not one of ours
}

TEST_CASE("mavlink: every message round-trips through encode and the parser and decode") {
  std::mt19937_64 rng(1);
  const auto round_trip = [&](auto tag) {
    using M = typename decltype(tag)::type;
    CAPTURE(M::kName);
    for (int i = 0; i < 300; ++i) {
      const double zero_p = std::array{1.0, 0.0, 0.3, 0.8}[static_cast<std::size_t>(i % 4)];
      const mv::Message msg = t::random_message<M>(rng, zero_p);
      const mv::FrameHeader header{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(rng()),
                                   static_cast<std::uint8_t>(rng())};
      const Bytes bytes = mv::encode(msg, header);
      mv::Parser parser;
      const auto frames = parse(parser, bytes);
      REQUIRE(frames.size() == 1);
      CHECK(frames[0].header() == header);
      CHECK(frames[0].message_id == M::kId);
      CHECK(frames[0].version == mv::ProtocolVersion::v2);
      CHECK(parser.pending() == 0);
      const mv::Message back = mv::decode(frames[0]);
      REQUIRE(std::holds_alternative<M>(back));
      CHECK(same_message(back, msg));
      const auto problems = t::compare(back, t::read_lines_from_text(t::to_line(msg, header, bytes)).at(0));
      CHECK(problems.empty());
    }
  };
  t::for_each_message_type(round_trip);
}

TEST_CASE("mavlink: frames are byte-identical to the frames node-mavlink encodes") {
  int identical = 0;
  for (const t::FrameLine& line : node_frames()) {
    CAPTURE(line.line_number);
    CAPTURE(line.name);
    mv::Parser parser;
    const auto frames = parse(parser, line.bytes);
    if (line.name == "ATTITUDE") {  // not ours: skipped (checked in its own case)
      CHECK(frames.empty());
      continue;
    }
    REQUIRE(frames.size() == 1);
    const mv::Frame& f = frames[0];
    CHECK(f.header() == line.header);
    const mv::Message msg = mv::decode(f);
    CHECK(mv::message_name(msg) == line.name);
    const auto problems = t::compare(msg, line);
    for (const auto& p : problems) FAIL_CHECK(p);
    if (f.signature || f.version == mv::ProtocolVersion::v1) continue;  // we write unsigned MAVLink 2 only
    const Bytes ours = mv::encode(msg, f.header());
    if (f.payload_length == 0) {
      continue;  // node-mavlink's all-zero payload: its own case
    }
    CHECK(t::to_hex(ours) == t::to_hex(line.bytes));
    identical += ours == line.bytes;
  }
  CHECK(identical == 23);  // 27 frames: 1 MAVLink 1, 1 signed, 1 all-zero, 1 unknown id
}

TEST_CASE("mavlink: an all-zero payload keeps one byte where node-mavlink sends none") {
  // mavlink.io, payload truncation: the first byte is never truncated. node-mavlink 2.3.0
  // truncates it too; the frame is valid either way, and we read its zero-length payload.
  const t::FrameLine& node = node_frame("MISSION_ITEM_REACHED", 0);
  const auto frames = parse(node.bytes);
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].payload_length == 0);
  const mv::Message msg = mv::decode(frames[0]);
  CHECK(std::get<mv::MissionItemReached>(msg).seq == 0);
  const Bytes ours = mv::encode(msg, frames[0].header());
  CHECK(ours.size() == node.bytes.size() + 1);
  CHECK(ours[1] == 1);
  CHECK(ours[10] == 0);
  CHECK(parse(ours).size() == 1);
  // Every message all zeros: one payload byte (HEARTBEAT's default mavlink_version, 3, is its
  // last byte: 9).
  const auto one_byte = [](auto tag) {
    using M = typename decltype(tag)::type;
    CAPTURE(M::kName);
    CHECK(mv::encode(M{}, {})[1] == (std::is_same_v<M, mv::Heartbeat> ? 9 : 1));
  };
  t::for_each_message_type(one_byte);
}

TEST_CASE("mavlink: trailing-zero truncation when encoding") {
  // Extensions zero: the payload ends with the base fields' last non-zero byte.
  mv::SysStatus status{.load = 312, .voltage_battery = 15840, .battery_remaining = 78};
  CHECK(mv::encode(status, {})[1] == 31);  // battery_remaining is the last base field
  status.battery_remaining = 0;
  CHECK(mv::encode(status, {})[1] == 16);  // ... and then voltage_battery (offset 14, 2 bytes)
  status.onboard_control_sensors_health_extended = 1;
  CHECK(mv::encode(status, {})[1] == 40);  // an extension: the full length but its zero high bytes
  CHECK(mv::encode(mv::MissionCurrent{.seq = 5}, {})[1] == 1);
  CHECK(mv::encode(mv::MissionCurrent{.seq = 256}, {})[1] == 2);
  CHECK(mv::encode(mv::CommandAck{.command = 400, .result = mv::mav_result::kAccepted}, {})[1] == 2);
  CHECK(mv::encode(mv::CommandAck{.command = 400, .target_component = 191}, {})[1] == 10);
  CHECK(mv::encode(mv::StatusText{.severity = 6, .text = "abc"}, {})[1] == 4);
  CHECK(mv::encode(mv::StatusText{.severity = 6, .text = std::string(50, 'x')}, {})[1] == 51);
  // A zero inside the payload is kept; only the tail goes.
  const Bytes ack = mv::encode(mv::CommandAck{.command = 0, .result = 4}, {});
  CHECK(ack[1] == 3);
  CHECK(mv::truncated_length(std::vector<std::uint8_t>{0, 0, 0}) == 1);
  CHECK(mv::truncated_length(std::vector<std::uint8_t>{0, 7, 0}) == 2);
  CHECK(mv::truncated_length(std::vector<std::uint8_t>{}) == 0);
}

TEST_CASE("mavlink: truncated payloads are zero-extended when decoding") {
  // GPS_RAW_INT: the receiver is sent 10 of its 52 bytes (time_usec and half of lat).
  const Bytes payload = {1, 2, 3, 4, 5, 6, 7, 8, 0x44, 0x33};
  const auto frames = parse(raw_frame(mv::GpsRawInt::kId, payload, mv::GpsRawInt::kCrcExtra));
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].payload_length == 10);
  const auto gps = std::get<mv::GpsRawInt>(mv::decode(frames[0]));
  CHECK(gps.time_usec == 0x0807060504030201ULL);
  CHECK(gps.lat == 0x3344);
  CHECK(gps.lon == 0);
  CHECK(gps.yaw == 0);
  // A payload of length 0: every field zero, STATUSTEXT's text empty.
  const auto empty = parse(raw_frame(mv::StatusText::kId, {}, mv::StatusText::kCrcExtra));
  REQUIRE(empty.size() == 1);
  CHECK(std::get<mv::StatusText>(mv::decode(empty[0])) == mv::StatusText{});
  // The base fields only (a MAVLink 1 sender's length): the extensions read zero.
  Bytes ack_payload = {0x90, 0x01, 0x00};
  const auto ack = parse(raw_frame(mv::CommandAck::kId, ack_payload, mv::CommandAck::kCrcExtra));
  REQUIRE(ack.size() == 1);
  CHECK(std::get<mv::CommandAck>(mv::decode(ack[0])) == mv::CommandAck{.command = 400});
  // The fixture's truncated frames (node-mavlink truncates them): all read with their zeros.
  const auto current = parse(node_frame("MISSION_CURRENT", 1).bytes);
  REQUIRE(current.size() == 1);
  CHECK(std::get<mv::MissionCurrent>(mv::decode(current[0])) == mv::MissionCurrent{.seq = 5});
}

TEST_CASE("mavlink: frames split across chunks of every size come out whole and in order") {
  Bytes stream;
  std::size_t ours = 0;
  for (const auto& l : node_frames()) {
    stream.insert(stream.end(), l.bytes.begin(), l.bytes.end());
    ours += l.name != "ATTITUDE";
  }
  // The fixture ends with ATTITUDE, believed (and skipped) once the next frame starts.
  const Bytes hb = mv::encode(kPx4Heartbeat, {});
  stream.insert(stream.end(), hb.begin(), hb.end());
  ++ours;
  const std::vector<mv::Frame> whole = parse(stream);
  REQUIRE(whole.size() == ours);
  std::mt19937 rng(3);
  for (const std::size_t chunk : std::initializer_list<std::size_t>{1, 2, 3, 5, 7, 13, 64, 255, 281, 1000, 0}) {
    CAPTURE(chunk);
    mv::Parser parser;
    std::vector<mv::Frame> frames;
    for (std::size_t at = 0; at < stream.size();) {
      const std::size_t size = chunk != 0 ? chunk : std::uniform_int_distribution<std::size_t>(1, 40)(rng);
      const std::size_t n = std::min(stream.size() - at, size);
      for (auto& f : parse(parser, std::span<const std::uint8_t>(stream.data() + at, n))) frames.push_back(f);
      at += n;
      CHECK(parser.pending() <= mv::kMaxFrameLength);
    }
    REQUIRE(frames.size() == whole.size());
    for (std::size_t i = 0; i < frames.size(); ++i) CHECK(frames[i] == whole[i]);
    CHECK(parser.stats().unknown_ids == 1);
    CHECK(parser.stats().dropped_bytes == 0);
    check_accounting(parser, frames);
  }
}

TEST_CASE("mavlink: garbage before between and after frames is dropped and counted") {
  const Bytes hb = mv::encode(kPx4Heartbeat, {});
  const Bytes text = mv::encode(mv::StatusText{.severity = 6, .text = "hello"}, {});
  const Bytes junk = {0x00, 0x11, 0x55, 0xAA, 0xFF, 0x42};  // no start byte
  mv::Parser parser;
  const auto frames = parse(parser, concat({junk, hb, junk, junk, text, junk}));
  REQUIRE(frames.size() == 2);
  CHECK(std::get<mv::Heartbeat>(mv::decode(frames[0])) == kPx4Heartbeat);
  CHECK(std::get<mv::StatusText>(mv::decode(frames[1])).text == "hello");
  CHECK(parser.stats().dropped_bytes == 4 * junk.size());
  CHECK(parser.pending() == 0);
  check_accounting(parser, frames);

  // Start bytes inside the garbage: a false MAVLink 2 header of a known id and a false
  // MAVLink 1 one fail their checksums, a false header of an unknown id is not followed by a
  // start byte; the good frames behind them all come out.
  const Bytes tricky = {0xFD, 0x05, 0x00, 0x00, 0x01, 0x01, 0x01, 0x00, 0x00, 0x00,  // HEARTBEAT, 5 bytes, bad CRC
                        0xFE, 0x03, 0x00, 0x01, 0x01, 0x4C,                          // v1 COMMAND_LONG
                        0xFD, 0x02, 0x00, 0x00, 0x01, 0x01, 0x01, 0x1E, 0x00, 0x00, 0x12};  // ATTITUDE, cut
  mv::Parser p2;
  std::vector<mv::Frame> got;
  for (int i = 0; i < 3; ++i) {
    for (auto& f : parse(p2, concat({tricky, hb, text}))) got.push_back(f);
  }
  CHECK(got.size() == 6);
  CHECK(p2.stats().crc_errors >= 2);
  CHECK(p2.stats().unknown_ids == 0);
  check_accounting(p2, got);
}

TEST_CASE("mavlink: unknown message ids are skipped whole and counted") {
  const t::FrameLine& attitude = node_frame("ATTITUDE");
  const Bytes hb = mv::encode(kPx4Heartbeat, {});
  mv::Parser parser;
  // An unknown frame is believed once the byte after it starts another frame.
  CHECK(parse(parser, attitude.bytes).empty());
  CHECK(parser.pending() == attitude.bytes.size());
  const auto frames = parse(parser, concat({hb, attitude.bytes, attitude.bytes, hb}));
  CHECK(frames.size() == 2);
  CHECK(parser.stats().unknown_ids == 3);
  CHECK(parser.stats().skipped_bytes == 3 * attitude.bytes.size());
  CHECK(parser.stats().dropped_bytes == 0);
  check_accounting(parser, frames);
  // Followed by garbage instead: its start byte is garbage, the rest read again.
  mv::Parser p2;
  const auto f2 = parse(p2, concat({attitude.bytes, Bytes{0x00}, hb}));
  CHECK(f2.size() == 1);
  CHECK(p2.stats().unknown_ids == 0);
  CHECK(p2.stats().dropped_bytes == attitude.bytes.size() + 1);
}

TEST_CASE("mavlink: a corrupted frame is never accepted and the frames after it are") {
  // Every bit of a COMMAND_LONG frame flipped in turn, then good frames: no corrupted frame
  // comes out as a message, and the good ones behind it all do.
  const mv::CommandLong cmd{
      .target_system = 1, .target_component = 1, .command = mv::mav_cmd::kNavTakeoff, .param7 = 30.0F};
  const Bytes good = mv::encode(cmd, {.sequence = 3});
  const Bytes hb = mv::encode(kPx4Heartbeat, {.sequence = 4});
  Bytes tail;  // enough good frames to complete any length the corruption declares
  for (int i = 0; i < 16; ++i) tail.insert(tail.end(), hb.begin(), hb.end());
  int rejected_by_crc = 0;
  for (std::size_t byte = 0; byte < good.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      CAPTURE(byte);
      CAPTURE(bit);
      Bytes bad = good;
      bad[byte] = static_cast<std::uint8_t>(bad[byte] ^ (1u << bit));
      mv::Parser parser;
      const auto frames = parse(parser, concat({bad, tail}));
      std::size_t heartbeats = 0;
      for (const auto& f : frames) {
        const mv::Message m = mv::decode(f);
        REQUIRE(std::holds_alternative<mv::Heartbeat>(m));  // never the corrupted command
        heartbeats += std::get<mv::Heartbeat>(m) == kPx4Heartbeat;
      }
      CHECK(heartbeats == 16);
      rejected_by_crc += parser.stats().crc_errors > 0;
      check_accounting(parser, frames);
    }
  }
  CHECK(rejected_by_crc > static_cast<int>(good.size() * 8 * 3 / 4));
}

TEST_CASE("mavlink: a frame cut short is never accepted and the next frame is") {
  const Bytes good = mv::encode(mv::HomePosition{.latitude = 507332101,
                                                 .longitude = 71038874,
                                                 .altitude = 61230,
                                                 .q = {1.0F, 0.0F, 0.0F, 0.0F},
                                                 .time_usec = 42},
                                {.sequence = 1});
  const Bytes hb = mv::encode(kPx4Heartbeat, {.sequence = 2});
  Bytes tail;
  for (int i = 0; i < 40; ++i) tail.insert(tail.end(), hb.begin(), hb.end());
  for (std::size_t cut = 1; cut < good.size(); ++cut) {
    CAPTURE(cut);
    mv::Parser parser;
    // The cut frame alone: nothing yet, its bytes held.
    CHECK(parse(parser, std::span<const std::uint8_t>(good.data(), cut)).empty());
    CHECK(parser.pending() <= cut);
    const auto frames = parse(parser, tail);
    CHECK(frames.size() == 40);
    for (const auto& f : frames) CHECK(f.message_id == mv::Heartbeat::kId);
    check_accounting(parser, frames);
  }
}

TEST_CASE("mavlink: a payload longer than the message is read, its extra bytes ignored and counted") {
  // A HEARTBEAT of 10 bytes (9 defined) with a right checksum: a sender whose definition has an
  // extension field ours lacks. MAVLink 2 receivers read the fields they know and ignore the rest.
  const Bytes long_hb = raw_frame(mv::Heartbeat::kId, Bytes(10, 1), mv::Heartbeat::kCrcExtra);
  const Bytes long_ack = raw_frame(mv::CommandAck::kId, Bytes(11, 2), mv::CommandAck::kCrcExtra);
  const Bytes hb = mv::encode(kPx4Heartbeat, {});
  mv::Parser parser;
  const auto frames = parse(parser, concat({long_hb, hb, long_ack, hb}));
  REQUIRE(frames.size() == 4);
  CHECK(parser.stats().longer_payloads == 2);
  CHECK(parser.stats().skipped_bytes == 0);
  CHECK(parser.stats().crc_errors == 0);
  check_accounting(parser, frames);
  // The known fields as the first 9 (10) bytes say; the same message as the payload cut to them.
  const Bytes short_hb = raw_frame(mv::Heartbeat::kId, Bytes(9, 1), mv::Heartbeat::kCrcExtra);
  CHECK(mv::decode(frames[0]) == mv::decode(parse(short_hb).at(0)));
  const Bytes short_ack = raw_frame(mv::CommandAck::kId, Bytes(10, 2), mv::CommandAck::kCrcExtra);
  CHECK(mv::decode(frames[2]) == mv::decode(parse(short_ack).at(0)));
  // A wrong checksum is still refused, longer or not.
  Bytes bad = long_hb;
  bad[bad.size() - 1] ^= 0x01;
  CHECK(parse(bad).empty());
}

TEST_CASE("mavlink: signed frames are accepted with their signature skipped unverified") {
  const t::FrameLine* line = nullptr;
  for (const auto& l : node_frames()) {
    if (l.bytes[2] == mv::kIncompatFlagSigned) line = &l;
  }
  REQUIRE(line != nullptr);
  mv::Parser parser;
  const auto frames = parse(parser, concat({line->bytes, mv::encode(kPx4Heartbeat, {})}));
  REQUIRE(frames.size() == 2);
  REQUIRE(frames[0].signature.has_value());
  CHECK(frames[0].signature->link_id == 7);
  // 2025-01-01 00:00 UTC in 10 us since 2015-01-01: 3653 days.
  CHECK(frames[0].signature->timestamp == 3653ULL * 86400ULL * 100000ULL);
  CHECK(
      std::equal(frames[0].signature->signature.begin(), frames[0].signature->signature.end(), line->bytes.end() - 6));
  CHECK(t::compare(mv::decode(frames[0]), *line).empty());
  CHECK(parser.stats().signed_frames == 1);
  check_accounting(parser, frames);
  // A bit flipped in the signature goes unnoticed: the codec does not verify signatures.
  Bytes forged = line->bytes;
  forged.at(forged.size() - 1) = static_cast<std::uint8_t>(forged.at(forged.size() - 1) ^ 1u);
  CHECK(parse(forged).size() == 1);
}

TEST_CASE("mavlink: incompat flags other than signing are rejected") {
  const Bytes hb = mv::encode(kPx4Heartbeat, {});
  for (const int flags : {0x02, 0x80, 0x03}) {
    CAPTURE(flags);
    const Bytes odd = raw_frame(mv::Heartbeat::kId, Bytes(hb.begin() + 10, hb.end() - 2), mv::Heartbeat::kCrcExtra,
                                static_cast<std::uint8_t>(flags));
    mv::Parser parser;
    const auto frames = parse(parser, concat({odd, hb}));
    REQUIRE(frames.size() == 1);
    CHECK(frames[0].incompat_flags == 0);
    CHECK(parser.stats().incompatible_flags == 1);
  }
}

TEST_CASE("mavlink: MAVLink 1 frames are accepted") {
  const t::FrameLine* line = nullptr;
  for (const auto& l : node_frames()) {
    if (l.bytes[0] == mv::kStartV1) line = &l;
  }
  REQUIRE(line != nullptr);
  mv::Parser parser;
  const auto frames = parse(parser, concat({line->bytes, mv::encode(kPx4Heartbeat, {}), line->bytes}));
  REQUIRE(frames.size() == 3);
  CHECK(frames[0].version == mv::ProtocolVersion::v1);
  CHECK(frames[0].header() == line->header);
  const auto hb = std::get<mv::Heartbeat>(mv::decode(frames[0]));
  CHECK(hb.type == mv::mav_type::kOnboardController);
  CHECK(hb.autopilot == mv::mav_autopilot::kInvalid);
  CHECK(t::compare(mv::decode(frames[0]), *line).empty());
  CHECK(parser.stats().mavlink1_frames == 2);
}

TEST_CASE("mavlink: encode rejects texts that do not fit naming the field") {
  CHECK_THROWS_WITH_AS((void)mv::encode(mv::StatusText{.severity = 6, .text = std::string(51, 'x')}, {}),
                       doctest::Contains("STATUSTEXT.text must be at most 50 bytes (got 51)"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)mv::encode(mv::StatusText{.text = std::string("a\0b", 3)}, {}),
                       doctest::Contains("STATUSTEXT.text must not contain a NUL byte"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)mv::encode(mv::CameraImageCaptured{.file_url = std::string(206, 'u')}, {}),
                       doctest::Contains("CAMERA_IMAGE_CAPTURED.file_url must be at most 205 bytes"),
                       std::invalid_argument);
  const mv::Message as_variant = mv::StatusText{.text = std::string(60, 'y')};
  CHECK_THROWS_AS((void)mv::encode(as_variant, {}), std::invalid_argument);
  CHECK_NOTHROW((void)mv::encode(mv::StatusText{.text = std::string(50, 'x')}, {}));
  CHECK_NOTHROW((void)mv::encode(mv::CameraImageCaptured{.file_url = std::string(205, 'u')}, {}));
}

TEST_CASE("mavlink: decode rejects an unknown id, reads a longer payload as far as the message goes") {
  mv::Frame unknown;
  unknown.message_id = 30;
  CHECK_THROWS_WITH_AS((void)mv::decode(unknown), doctest::Contains("message id 30"), std::invalid_argument);
  // A HEARTBEAT with a tenth byte (an extension our definition lacks): the nine known bytes.
  mv::Frame longer;
  longer.message_id = mv::Heartbeat::kId;
  longer.payload_length = 10;
  longer.payload = {1, 0, 0, 0, 2, 12, 0, 0, 3, 99};
  const auto hb = std::get<mv::Heartbeat>(mv::decode(longer));
  longer.payload_length = 9;
  longer.payload[9] = 0;
  CHECK(hb == std::get<mv::Heartbeat>(mv::decode(longer)));
  // Bytes past payload_length are not read: the payload is zero-extended whatever they hold.
  mv::Frame dirty;
  dirty.message_id = mv::MissionItemReached::kId;
  dirty.payload_length = 1;
  dirty.payload = {7, 9, 9, 9};
  CHECK(std::get<mv::MissionItemReached>(mv::decode(dirty)).seq == 7);
}

TEST_CASE("mavlink: random streams never throw and every byte is accounted for") {
  // Valid frames of every message, garbage, bit flips and cuts, in random chunks.
  std::mt19937_64 rng(11);
  std::vector<Bytes> pieces;
  for (const auto& l : node_frames()) pieces.push_back(l.bytes);
  for (int i = 0; i < 20; ++i) pieces.push_back(mv::encode(t::random_message<mv::CameraImageCaptured>(rng, 0.3), {}));
  for (int round = 0; round < 200; ++round) {
    Bytes stream;
    for (int k = 0; k < 30; ++k) {
      Bytes piece = pieces[std::uniform_int_distribution<std::size_t>(0, pieces.size() - 1)(rng)];
      switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
        case 0: piece[std::uniform_int_distribution<std::size_t>(0, piece.size() - 1)(rng)] ^= 0x10; break;
        case 1: piece.resize(std::uniform_int_distribution<std::size_t>(0, piece.size())(rng)); break;
        case 2:
          for (auto& b : piece) b = static_cast<std::uint8_t>(rng());
          break;
        default: break;
      }
      stream.insert(stream.end(), piece.begin(), piece.end());
    }
    mv::Parser parser;
    std::vector<mv::Frame> frames;
    for (std::size_t at = 0; at < stream.size();) {
      const std::size_t n = std::min(stream.size() - at, std::uniform_int_distribution<std::size_t>(1, 100)(rng));
      for (auto& f : parse(parser, std::span<const std::uint8_t>(stream.data() + at, n))) frames.push_back(f);
      at += n;
    }
    for (const auto& f : frames) {
      const mv::Message m = mv::decode(f);  // never throws for a parsed frame
      const Bytes again = mv::encode(m, f.header());
      const auto back = parse(again);
      REQUIRE(back.size() == 1);
      CHECK(same_message(mv::decode(back[0]), m));
    }
    check_accounting(parser, frames);
    CHECK(parser.pending() <= mv::kMaxFrameLength);
  }
}

TEST_CASE("mavlink: reset forgets held bytes and counts") {
  mv::Parser parser;
  const Bytes hb = mv::encode(kPx4Heartbeat, {});
  CHECK(parse(parser, std::span<const std::uint8_t>(hb.data(), 5)).empty());
  CHECK(parser.pending() == 5);
  parser.reset();
  CHECK(parser.pending() == 0);
  CHECK(parser.stats() == mv::ParseStats{});
  CHECK(parse(parser, hb).size() == 1);
}
