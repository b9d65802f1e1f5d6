#pragma once
/// @file
/// The YAML reading and writing shared by every file adaptseg reads (field.yaml, model files,
/// network metadata, ensemble.yaml, a live folder's area.yaml): a reader of mappings whose
/// errors name the file and the key, and emitters that write numbers through the one
/// locale-independent codec (number_text.hpp), so that a file written under any global locale
/// reads back under any other.

#include <adaptseg/vision/detail/number_text.hpp>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstddef>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// Throws std::invalid_argument("<where>: <what>").
[[noreturn]] inline void yaml_error(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

/// Runs `read` so that every error it throws names the file `where` once: yaml-cpp's own
/// exceptions become std::invalid_argument("<where>: bad value: ..."), the others get the
/// prefix unless they already start with it.
template <class F>
decltype(auto) naming_file(const std::string& where, F&& read) {
  try {
    return std::forward<F>(read)();
  } catch (const YAML::Exception& ex) {
    yaml_error(where, std::string("bad value: ") + ex.what());
  } catch (const std::invalid_argument& ex) {
    const std::string what = ex.what();
    if (what.rfind(where, 0) == 0) throw;
    yaml_error(where, what);
  }
}

/// The document `load()` parses (YAML::Load of a text or YAML::LoadFile), which must be a
/// mapping: a parse error becomes "<where>: YAML error: ...", another node "<where>: not
/// <what> (the document must be a mapping)".
template <class F>
[[nodiscard]] YAML::Node yaml_mapping(const std::string& where, const std::string& what, F&& load) {
  YAML::Node root;
  try {
    root = std::forward<F>(load)();
  } catch (const YAML::Exception& ex) {
    yaml_error(where, std::string("YAML error: ") + ex.what());
  }
  if (!root.IsMap()) yaml_error(where, "not " + what + " (the document must be a mapping)");
  return root;
}

/// A reader of one YAML mapping of an adaptseg file: every value read through the number codec
/// (number_text.hpp), every error naming the file and the key's path (`gain_model.O.y_std`,
/// `classes[2].color`).
class YamlReader {
 public:
  YamlReader(YAML::Node node, std::string where) : node_(std::move(node)), where_(std::move(where)) {}

  /// Refuses a key that is not one of `known`: "unknown key '<path>' (known: a, b, c)".
  void only_keys(std::initializer_list<const char*> known) const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "<non-scalar>";
      if (std::any_of(known.begin(), known.end(), [&](const char* k) { return key == k; })) continue;
      std::string names;
      for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
      yaml_error(where_, "unknown key '" + path(key.c_str()) + "' (known: " + names + ")");
    }
  }

  [[nodiscard]] bool has(const char* key) const { return static_cast<bool>(node_[key]); }
  [[nodiscard]] YAML::Node node(const char* key) const {
    const YAML::Node n = node_[key];
    if (!n) yaml_error(where_, std::string("missing key '") + path(key) + "'");
    return n;
  }
  [[nodiscard]] YamlReader map(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsMap()) yaml_error(where_, "'" + path(key) + "' must be a mapping");
    return YamlReader(n, where_, path(key));
  }
  [[nodiscard]] std::string text(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsScalar()) yaml_error(where_, "'" + path(key) + "' must be a scalar");
    return n.Scalar();
  }
  [[nodiscard]] double number(const char* key) const { return number_of(node(key), path(key)); }
  [[nodiscard]] long long integer(const char* key, long long lo, long long hi) const {
    return integer_of(node(key), path(key), lo, hi);
  }
  [[nodiscard]] bool flag(const char* key) const {
    const std::string t = text(key);
    if (t != "true" && t != "false") yaml_error(where_, "'" + path(key) + "' must be true or false (got '" + t + "')");
    return t == "true";
  }
  [[nodiscard]] std::vector<double> numbers(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsSequence()) yaml_error(where_, "'" + path(key) + "' must be a list of numbers");
    std::vector<double> out;
    for (std::size_t k = 0; k < n.size(); ++k)
      out.push_back(number_of(n[k], path(key) + "[" + std::to_string(k) + "]"));
    return out;
  }
  /// The list `key` of mappings, a reader for each (`key[i]` in its errors).
  [[nodiscard]] std::vector<YamlReader> maps(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsSequence()) yaml_error(where_, "'" + path(key) + "' must be a list of mappings");
    std::vector<YamlReader> out;
    for (std::size_t k = 0; k < n.size(); ++k) {
      const std::string at = path(key) + "[" + std::to_string(k) + "]";
      if (!n[k].IsMap()) yaml_error(where_, "'" + at + "' must be a mapping");
      out.push_back(YamlReader(n[k], where_, at));
    }
    return out;
  }
  /// The list `key` of integers, each in [lo, hi].
  [[nodiscard]] std::vector<long long> integers(const char* key, long long lo, long long hi) const {
    const YAML::Node n = node(key);
    if (!n.IsSequence()) yaml_error(where_, "'" + path(key) + "' must be a list of integers");
    std::vector<long long> out;
    for (std::size_t k = 0; k < n.size(); ++k)
      out.push_back(integer_of(n[k], path(key) + "[" + std::to_string(k) + "]", lo, hi));
    return out;
  }
  [[nodiscard]] std::vector<std::string> texts(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsSequence()) yaml_error(where_, "'" + path(key) + "' must be a list");
    std::vector<std::string> out;
    for (const auto& v : n) {
      if (!v.IsScalar()) yaml_error(where_, "'" + path(key) + "' must be a list of names");
      out.push_back(v.Scalar());
    }
    return out;
  }
  [[nodiscard]] const std::string& where() const noexcept { return where_; }
  [[nodiscard]] std::string path(const char* key) const { return prefix_.empty() ? key : prefix_ + "." + key; }
  [[nodiscard]] double number_of(const YAML::Node& n, const std::string& what) const {
    const auto v = n.IsScalar() ? parse_number(n.Scalar()) : std::nullopt;
    if (!v)
      yaml_error(where_,
                 "'" + what + "' must be a finite number" + (n.IsScalar() ? " (got '" + n.Scalar() + "')" : ""));
    return *v;
  }
  [[nodiscard]] long long integer_of(const YAML::Node& n, const std::string& what, long long lo, long long hi) const {
    const auto v = n.IsScalar() ? parse_integer(n.Scalar(), lo, hi) : std::nullopt;
    if (!v)
      yaml_error(where_, "'" + what + "' must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                             "]" + (n.IsScalar() ? " (got '" + n.Scalar() + "')" : ""));
    return *v;
  }

 private:
  YamlReader(YAML::Node node, std::string where, std::string prefix)
      : node_(std::move(node)), where_(std::move(where)), prefix_(std::move(prefix)) {}
  YAML::Node node_;
  std::string where_;
  std::string prefix_;
};

inline YAML::Emitter& emit_number(YAML::Emitter& e, double v) { return e << format_number(v); }

inline YAML::Emitter& emit_numbers(YAML::Emitter& e, const Eigen::Ref<const Eigen::VectorXd>& v) {
  e << YAML::Flow << YAML::BeginSeq;
  for (Eigen::Index k = 0; k < v.size(); ++k) emit_number(e, v(k));
  return e << YAML::EndSeq;
}

inline YAML::Emitter& emit_numbers(YAML::Emitter& e, const std::vector<double>& v) {
  return emit_numbers(e, Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
}

inline const char* flag_text(bool b) { return b ? "true" : "false"; }

}  // namespace adaptseg::detail
