#pragma once
// The text form of MAVLink frames shared by the tests of adaptseg::mavlink and node-mavlink
// (tests/mavlink/frame_lines.mjs writes and reads the same lines):
//
//   NAME SEQ SYSID COMPID HEX field=value field=value ...
//
// one frame per line ('#' starts a comment line): the message name of the definitions, the
// header the sender chose, the frame's bytes in hex, and every field of the message by its
// name in the definitions. Integers are decimal; floats the shortest decimal that reads back
// to the same float, or NaN, Infinity, -Infinity, -0; arrays comma-separated; char[N] fields
// the hex of their bytes up to the first NUL.

#include <adaptseg/mavlink.hpp>

#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <istream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <variant>
#include <vector>

namespace adaptseg::mavlink::test {

inline std::string to_hex(const std::uint8_t* data, std::size_t size) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * size);
  for (std::size_t i = 0; i < size; ++i) {
    out += kDigits[data[i] >> 4];
    out += kDigits[data[i] & 0x0F];
  }
  return out;
}
inline std::string to_hex(const std::vector<std::uint8_t>& bytes) { return to_hex(bytes.data(), bytes.size()); }

inline std::vector<std::uint8_t> from_hex(std::string_view hex) {
  if (hex.size() % 2 != 0) throw std::invalid_argument("odd number of hex digits: " + std::string(hex));
  std::vector<std::uint8_t> out(hex.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i) {
    unsigned v = 0;
    const auto [ptr, ec] = std::from_chars(hex.data() + 2 * i, hex.data() + 2 * i + 2, v, 16);
    if (ec != std::errc() || ptr != hex.data() + 2 * i + 2) throw std::invalid_argument("bad hex: " + std::string(hex));
    out[i] = static_cast<std::uint8_t>(v);
  }
  return out;
}

template <typename T>
std::string number_text(T value) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isnan(value)) return "NaN";
    if (std::isinf(value)) return value > 0 ? "Infinity" : "-Infinity";
    if (value == 0 && std::signbit(value)) return "-0";
    std::array<char, 64> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), value);
    return std::string(buf.data(), res.ptr);
  } else if constexpr (std::is_signed_v<T>) {
    return std::to_string(static_cast<long long>(value));
  } else {
    return std::to_string(static_cast<unsigned long long>(value));
  }
}

template <typename T>
T parse_number(std::string_view text) {
  if constexpr (std::is_floating_point_v<T>) {
    if (text == "NaN") return std::numeric_limits<T>::quiet_NaN();
    if (text == "Infinity") return std::numeric_limits<T>::infinity();
    if (text == "-Infinity") return -std::numeric_limits<T>::infinity();
    // The peer writes the double that holds the float: read it as a double, then narrow (exact).
    double d = 0.0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), d);
    if (ec != std::errc() || ptr != text.data() + text.size()) {
      throw std::invalid_argument("bad number: " + std::string(text));
    }
    return static_cast<T>(d);
  } else {
    using Wide = std::conditional_t<std::is_signed_v<T>, long long, unsigned long long>;
    Wide v = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || ptr != text.data() + text.size() || v < static_cast<Wide>(std::numeric_limits<T>::min()) ||
        v > static_cast<Wide>(std::numeric_limits<T>::max())) {
      throw std::invalid_argument("bad integer: " + std::string(text));
    }
    return static_cast<T>(v);
  }
}

/// Same value, bit for bit for floats (NaN equals NaN, -0 differs from 0).
template <typename T>
bool same_value(T a, T b) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isnan(a) && std::isnan(b)) return true;
    return std::memcmp(&a, &b, sizeof(T)) == 0;
  } else {
    return a == b;
  }
}

/// Calls f(std::type_identity<M>{}) for every message type M of Message.
template <typename F>
void for_each_message_type(F&& f) {
  [&]<typename... Ms>(const std::variant<Ms...>*) {
    (f(std::type_identity<Ms>{}), ...);
  }(static_cast<const Message*>(nullptr));
}

/// One line of the format.
struct FrameLine {
  std::string name;
  FrameHeader header;
  std::vector<std::uint8_t> bytes;
  std::map<std::string, std::string> fields;
  int line_number = 0;
};

/// Renders a message's fields as name=value tokens.
template <typename Msg>
struct RenderVisitor {
  const Msg& msg;
  std::string out;
  template <typename T>
  void field(std::string_view name, T Msg::*member) {
    out += ' ';
    out += name;
    out += '=';
    const T& v = msg.*member;
    if constexpr (detail::WireField<T>::count == 0) {
      out += number_text(v);
    } else {
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (i > 0) out += ',';
        out += number_text(v[i]);
      }
    }
  }
  void text(std::string_view name, std::string Msg::*member, std::size_t) {
    const std::string& s = msg.*member;
    out += ' ';
    out += name;
    out += '=';
    out += to_hex(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  }
  void extensions() {}
};

inline std::string to_line(const Message& msg, const FrameHeader& h, const std::vector<std::uint8_t>& bytes) {
  return std::visit(
      [&](const auto& m) {
        using M = std::decay_t<decltype(m)>;
        RenderVisitor<M> v{m, {}};
        M::fields(v);
        return std::string(M::kName) + ' ' + std::to_string(h.sequence) + ' ' + std::to_string(h.system_id) + ' ' +
               std::to_string(h.component_id) + ' ' + to_hex(bytes) + v.out;
      },
      msg);
}

/// Parses the lines of `in`; `source` names it in error messages.
inline std::vector<FrameLine> read_lines(std::istream& in, const std::string& source) {
  std::vector<FrameLine> out;
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    const std::string where = source + ":" + std::to_string(number);
    std::istringstream is(line);
    FrameLine fl;
    fl.line_number = number;
    std::string seq, sys, comp, hex;
    if (!(is >> fl.name >> seq >> sys >> comp >> hex)) throw std::runtime_error(where + ": short line");
    fl.header = {parse_number<std::uint8_t>(seq), parse_number<std::uint8_t>(sys), parse_number<std::uint8_t>(comp)};
    fl.bytes = from_hex(hex);
    for (std::string token; is >> token;) {
      const auto eq = token.find('=');
      if (eq == std::string::npos) throw std::runtime_error(where + ": bad token " + token);
      fl.fields[token.substr(0, eq)] = token.substr(eq + 1);
    }
    out.push_back(std::move(fl));
  }
  return out;
}

inline std::vector<FrameLine> read_lines(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  return read_lines(in, path);
}

inline std::vector<FrameLine> read_lines_from_text(const std::string& text) {
  std::istringstream in(text);
  return read_lines(in, "text");
}

/// Compares a decoded message with a line's fields; appends one text per difference.
template <typename Msg>
struct CompareVisitor {
  const Msg& msg;
  const std::map<std::string, std::string>& fields;
  std::vector<std::string>& problems;
  std::size_t seen = 0;

  const std::string* value_of(std::string_view name) {
    const auto it = fields.find(std::string(name));
    if (it == fields.end()) {
      problems.push_back(std::string(Msg::kName) + "." + std::string(name) + ": missing from the line");
      return nullptr;
    }
    ++seen;
    return &it->second;
  }
  template <typename T>
  void field(std::string_view name, T Msg::*member) {
    const std::string* text = value_of(name);
    if (text == nullptr) return;
    const T& got = msg.*member;
    bool same = true;
    try {
      if constexpr (detail::WireField<T>::count == 0) {
        same = same_value(got, parse_number<T>(*text));
      } else {
        std::vector<std::string> parts;
        std::string part;
        std::istringstream is(*text);
        while (std::getline(is, part, ',')) parts.push_back(part);
        same = parts.size() == got.size();
        for (std::size_t i = 0; same && i < got.size(); ++i) {
          same = same_value(got[i], parse_number<typename detail::WireField<T>::Element>(parts[i]));
        }
      }
    } catch (const std::exception& e) {
      problems.push_back(std::string(Msg::kName) + "." + std::string(name) + ": " + e.what());
      return;
    }
    if (!same) {
      RenderVisitor<Msg> r{msg, {}};
      r.field(name, member);
      problems.push_back(std::string(Msg::kName) + "." + std::string(name) + ": decoded" + r.out + ", line says " +
                         *text);
    }
  }
  void text(std::string_view name, std::string Msg::*member, std::size_t) {
    const std::string* text = value_of(name);
    if (text == nullptr) return;
    const std::vector<std::uint8_t> want = from_hex(*text);
    const std::string& got = msg.*member;
    if (got != std::string(want.begin(), want.end())) {
      problems.push_back(std::string(Msg::kName) + "." + std::string(name) + ": decoded " +
                         to_hex(reinterpret_cast<const std::uint8_t*>(got.data()), got.size()) + ", line says " +
                         *text);
    }
  }
  void extensions() {}
};

/// Differences between `msg` and the fields of `line` (a field missing, extra or different).
inline std::vector<std::string> compare(const Message& msg, const FrameLine& line) {
  std::vector<std::string> problems;
  std::visit(
      [&](const auto& m) {
        using M = std::decay_t<decltype(m)>;
        if (line.name != M::kName) {
          problems.push_back("decoded a " + std::string(M::kName) + ", the line is a " + line.name);
        }
        CompareVisitor<M> v{m, line.fields, problems};
        M::fields(v);
        if (v.seen != line.fields.size()) {
          problems.push_back(line.name + ": the line has " + std::to_string(line.fields.size()) +
                             " fields, the message " + std::to_string(v.seen));
        }
      },
      msg);
  return problems;
}

/// Assigns random values to a message's fields: integers over their whole range, floats of any
/// finite bit pattern or a special value, texts of 0..N non-zero bytes; each field zero with
/// probability `zero_p` (so that trailing-zero truncation is exercised).
template <typename Msg>
struct RandomVisitor {
  Msg& msg;
  std::mt19937_64& rng;
  double zero_p = 0.3;

  bool zero() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < zero_p; }
  template <typename T>
  T random_scalar() {
    if constexpr (std::is_floating_point_v<T>) {
      switch (std::uniform_int_distribution<int>(0, 11)(rng)) {
        case 0: return std::numeric_limits<T>::quiet_NaN();
        case 1: return std::numeric_limits<T>::infinity();
        case 2: return -std::numeric_limits<T>::infinity();
        case 3: return -0.0F;
        case 4: return std::numeric_limits<T>::denorm_min();
        case 5: return static_cast<T>(std::uniform_real_distribution<double>(-200.0, 200.0)(rng));
        default: {
          T v{};
          do {
            const auto bits = static_cast<detail::WireBits<T>>(rng());
            std::memcpy(&v, &bits, sizeof v);
          } while (!std::isfinite(v));
          return v;
        }
      }
    } else {
      return static_cast<T>(rng());
    }
  }
  template <typename T>
  void field(std::string_view, T Msg::*member) {
    T& v = msg.*member;
    if constexpr (detail::WireField<T>::count == 0) {
      v = zero() ? T{} : random_scalar<T>();
    } else {
      using E = typename detail::WireField<T>::Element;
      for (E& e : v) e = zero() ? E{} : random_scalar<E>();
    }
  }
  void text(std::string_view, std::string Msg::*member, std::size_t length) {
    std::string& s = msg.*member;
    s.clear();
    if (zero()) return;
    std::size_t n = std::uniform_int_distribution<std::size_t>(0, length)(rng);
    if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) n = length;  // full: no terminator on the wire
    for (std::size_t i = 0; i < n; ++i) s += static_cast<char>(std::uniform_int_distribution<int>(1, 255)(rng));
  }
  void extensions() {}
};

template <typename Msg>
Msg random_message(std::mt19937_64& rng, double zero_p) {
  Msg m{};
  RandomVisitor<Msg> v{m, rng, zero_p};
  Msg::fields(v);
  return m;
}

}  // namespace adaptseg::mavlink::test
