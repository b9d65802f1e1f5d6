#pragma once
/// @file
/// The MAVLink plain-text waypoint file (`QGC WPL 110`) of an export path, and the reader of it.
/// CMake target adaptseg::geo; docs/data_format.md, "Mission export".

#include <adaptseg/core/error.hpp>
#include <adaptseg/geo/detail/export_text.hpp>
#include <adaptseg/geo/export_path.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace adaptseg {

/// The MAVLink plain-text waypoint file of `path` (mavlink.io, "File Formats: Mission
/// Plain-Text File Format"): the line `QGC WPL 110`, then one tab-separated line per item,
/// `seq current frame command p1 p2 p3 p4 lat lon alt autocontinue`; line 0 is the home
/// position (current 1, MAV_FRAME_GLOBAL, NAV_WAYPOINT). Numbers are written in the C locale
/// with the shortest text that reads back exactly; NaN as `nan`, as QGroundControl does.
/// @throws std::invalid_argument for an empty path or invalid options.
inline std::string write_wpl(const ExportPath& path, const ExportOptions& options = {}) {
  detail::require_exportable(path, "write_wpl");
  std::string out = "QGC WPL 110\n";
  const auto line = [&](std::size_t seq, bool current, const MissionItem& item) {
    out += std::to_string(seq) + '\t' + (current ? '1' : '0') + '\t' + std::to_string(item.frame) + '\t' +
           std::to_string(item.command);
    for (double p : item.params) out += '\t' + detail::format_number(p);
    out += item.autocontinue ? "\t1\n" : "\t0\n";
  };
  line(0, true,
       {mavlink::kCmdNavWaypoint,
        mavlink::kFrameGlobal,
        {0.0, 0.0, 0.0, 0.0, path.home.latitude_deg, path.home.longitude_deg, path.home.altitude_m},
        true});
  const std::vector<MissionItem> items = mission_items(path, options);
  for (std::size_t i = 0; i < items.size(); ++i) line(i + 1, false, items[i]);
  return out;
}

namespace detail {

/// A line of a waypoint file split on runs of tabs, spaces and a trailing '\r'.
[[nodiscard]] inline std::vector<std::string_view> wpl_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  const auto is_space = [](char c) { return c == '\t' || c == ' ' || c == '\r'; };
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

/// The mission item of a waypoint file's line `at` of 12 `fields`, which must be number
/// `want_seq`.
/// @throws std::invalid_argument naming the line and field.
[[nodiscard]] inline MissionItem wpl_item(const std::vector<std::string_view>& fields, std::size_t want_seq,
                                          const std::string& at) {
  constexpr const char* kFmt = "WPL";
  long long ints[4];
  static constexpr const char* kIntNames[] = {"seq", "current", "frame", "command"};
  static constexpr long long kIntMax[] = {65535, 1, 255, 65535};
  for (int k = 0; k < 4; ++k)
    if (const auto v = parse_integer(fields[static_cast<std::size_t>(k)], 0, kIntMax[k]))
      ints[k] = *v;
    else
      export_parse_error(kFmt, at + ": " + kIntNames[k] + " must be an integer in 0.." + std::to_string(kIntMax[k]) +
                                   " (got '" + std::string(fields[static_cast<std::size_t>(k)]) + "')");
  if (static_cast<std::size_t>(ints[0]) != want_seq)
    export_parse_error(
        kFmt, at + ": seq " + std::to_string(ints[0]) + " out of order (want " + std::to_string(want_seq) + ")");
  MissionItem item;
  item.frame = static_cast<int>(ints[2]);
  item.command = static_cast<int>(ints[3]);
  for (std::size_t k = 0; k < 7; ++k)
    if (!wpl_parse(fields[4 + k], item.params[k]))
      export_parse_error(kFmt, at + ": field " + std::to_string(5 + k) + " (param" + std::to_string(k + 1) +
                                   ") is not a number: '" + std::string(fields[4 + k]) + "'");
  if (fields[11] != "0" && fields[11] != "1")
    export_parse_error(kFmt, at + ": autocontinue must be 0 or 1 (got '" + std::string(fields[11]) + "')");
  item.autocontinue = fields[11] == "1";
  check_item_position(item, kFmt, at);
  return item;
}

}  // namespace detail

/// Reads a MAVLink plain-text waypoint file (`QGC WPL 110`): line 0 is the home position,
/// the rest the mission items. Fields may be separated by tabs or spaces; blank lines and a
/// final newline are allowed; `\r\n` line ends and a UTF-8 byte-order mark are accepted.
/// Safe on any input: every failure is an exception.
/// @throws std::invalid_argument naming the line (1-based, the header is line 1) and field:
///         a wrong header, a line without 12 fields, a field that is not a number of the
///         right kind, a sequence number out of order, a position out of range, no home line.
inline MissionFile read_wpl(std::string_view text) {
  constexpr const char* kFmt = "WPL";
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  MissionFile out;
  bool header = false, home = false;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    const std::string at = "line " + std::to_string(line_no);
    const std::vector<std::string_view> fields = detail::wpl_fields(line);
    if (!header) {
      if (fields.size() != 3 || fields[0] != "QGC" || fields[1] != "WPL" || fields[2] != "110")
        detail::export_parse_error(kFmt, at + ": the first line must be 'QGC WPL 110'");
      header = true;
      continue;
    }
    if (fields.empty()) continue;
    if (fields.size() != 12)
      detail::export_parse_error(kFmt, at +
                                           ": want 12 fields (seq current frame command p1..p4 lat lon alt "
                                           "autocontinue), got " +
                                           std::to_string(fields.size()));
    const MissionItem item = detail::wpl_item(fields, home ? out.items.size() + 1 : 0, at);
    if (!home) {
      if (!std::isfinite(item.params[4]) || !std::isfinite(item.params[5]) || !std::isfinite(item.params[6]))
        detail::export_parse_error(kFmt,
                                   at + ": the home position must have a finite latitude, longitude and altitude");
      out.home = {item.params[4], item.params[5], item.params[6]};
      home = true;
    } else {
      out.items.push_back(item);
    }
  }
  if (!header) detail::export_parse_error(kFmt, "empty file (want 'QGC WPL 110' and a home line)");
  if (!home) detail::export_parse_error(kFmt, "no home line (seq 0) after the header");
  return out;
}

}  // namespace adaptseg
