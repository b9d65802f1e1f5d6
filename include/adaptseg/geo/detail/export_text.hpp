#pragma once
/// @file
/// Text helpers of the mission-file readers and writers (qgc_plan.hpp, wpl.hpp, geojson.hpp): errors that name
/// the format and the offending member, JSON member access with those errors, and the WPL
/// number reader (numbers are written by number_text.hpp's codec). Internal.

#include <adaptseg/vision/detail/number_text.hpp>

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>

namespace adaptseg::detail {

[[noreturn]] inline void export_parse_error(const char* format, const std::string& what) {
  throw std::invalid_argument(std::string(format) + ": " + what);
}

// --- JSON access that reports the path of the offending member ---

inline const nlohmann::json& json_member(const nlohmann::json& obj, const char* key, const char* format,
                                         const std::string& where) {
  if (!obj.is_object()) export_parse_error(format, where + " must be an object");
  const auto it = obj.find(key);
  if (it == obj.end()) export_parse_error(format, where + ": missing key '" + key + "'");
  return *it;
}

/// Requires the string member `key` of `obj` to be `want`.
inline void json_expect(const nlohmann::json& obj, const char* key, std::string_view want, const char* format) {
  const auto& j = json_member(obj, key, format, "the file");
  if (!j.is_string() || j.get_ref<const std::string&>() != want)
    export_parse_error(format, std::string(key) + " must be \"" + std::string(want) + "\"");
}

inline double json_number(const nlohmann::json& j, const char* format, const std::string& where) {
  if (!j.is_number()) export_parse_error(format, where + " must be a number");
  return j.get<double>();
}

inline long long json_integer(const nlohmann::json& j, long long lo, long long hi, const char* format,
                              const std::string& where) {
  const std::string range = " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi);
  if (j.is_number_unsigned()) {
    const auto u = j.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(hi)) export_parse_error(format, where + range);
    return static_cast<long long>(u);
  }
  if (!j.is_number_integer()) export_parse_error(format, where + range);
  const auto v = j.get<std::int64_t>();
  if (v < lo || v > hi) export_parse_error(format, where + range);
  return v;
}

inline const std::string& json_string(const nlohmann::json& j, const char* format, const std::string& where) {
  if (!j.is_string()) export_parse_error(format, where + " must be a string");
  return j.get_ref<const std::string&>();
}

inline nlohmann::json json_parse(std::string_view text, const char* format) {
  nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) export_parse_error(format, "not valid JSON");
  return j;
}

// --- WPL numbers: written by format_number (number_text.hpp); read as below ---

/// `token` as a double, locale-independent; unlike parse_number() a MAVLink parameter may be
/// NaN or infinite ("nan": not used by the command).
inline bool wpl_parse(std::string_view token, double& out) {
  const auto r = std::from_chars(token.data(), token.data() + token.size(), out);
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

}  // namespace adaptseg::detail
