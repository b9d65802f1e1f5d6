#pragma once
/// @file
/// Reader of the Gaussian-process text format of adaptseg 0.1 (`adaptseg.gaussian_process 1`),
/// kept so that files in that format still load: standalone GP files (gp_io.hpp) and the
/// decision functions embedded in decision-model files of format 1 (decision_model.hpp).
/// Nothing writes this format any more; gp_io.hpp writes YAML.
///
/// Format (one item per line; blank lines and lines starting with '#' are ignored):
/// @code
///   adaptseg.gaussian_process 1
///   kernel <K::kName>
///   log_parameters <p> <theta_1> ... <theta_p>
///   log_lower_bounds <p> ...
///   log_upper_bounds <p> ...
///   normalize_y <0|1>
///   y_mean <mean>
///   y_std <std>
///   initial_jitter <value>
///   max_jitter_attempts <count>
///   dimension <D>
///   samples <n>
///   <x_1> ... <x_D> <y>        (n lines)
///   end adaptseg.gaussian_process
/// @endcode

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gaussian_process.hpp>
#include <adaptseg/vision/detail/number_text.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <istream>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg::detail {

inline std::string gp_trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return std::string(s.substr(first, last - first + 1));
}

/// 'text', built without operator+ (GCC 12 -Wrestrict false positive on "'" + s + "'").
inline std::string gp_quote(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  out.push_back('\'');
  out.append(s);
  out.push_back('\'');
  return out;
}

inline std::vector<std::string_view> gp_split(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t') ++i;
    if (i > start) out.push_back(s.substr(start, i - start));
  }
  return out;
}

inline constexpr std::string_view kGpTextV1Magic = "adaptseg.gaussian_process";

/// Line tokenizer of the version-1 text: names the line of every error.
class GpTextV1Reader {
 public:
  explicit GpTextV1Reader(std::istream& is) : is_(is) {}

  [[nodiscard]] std::string where() const {
    return "GaussianProcess::load: line " + std::to_string(line_number_) + ": ";
  }

  /// The tokens of the next line that is neither blank nor a comment.
  std::vector<std::string> next(const std::string& expected) {
    while (true) {
      if (!std::getline(is_, line_))
        throw std::invalid_argument("GaussianProcess::load: unexpected end of input after line " +
                                    std::to_string(line_number_) + " (truncated file?), expected " + expected);
      ++line_number_;
      const std::string t = gp_trim(line_);
      if (t.empty() || t.front() == '#') continue;
      std::vector<std::string> out;
      for (auto v : gp_split(t)) out.emplace_back(v);
      return out;
    }
  }

  /// The next line, which must be `key` followed by `values` tokens.
  std::vector<std::string> expect(std::string_view key, std::size_t values) {
    auto t = next(gp_quote(key));
    require(!t.empty() && t[0] == key && t.size() == values + 1,
            where() + "expected '" + std::string(key) + "' followed by " + std::to_string(values) + " value(s), got",
            gp_quote(line_));
    return t;
  }

  [[nodiscard]] double parse_real(const std::string& token) const {
    const auto v = parse_number(token);
    require(v.has_value(), where() + "expected a finite number, got", gp_quote(token));
    return *v;
  }

  [[nodiscard]] long parse_integer(const std::string& token) const {
    const auto v = detail::parse_integer(token, std::numeric_limits<long>::min(), std::numeric_limits<long>::max());
    require(v.has_value(), where() + "expected an integer, got", gp_quote(token));
    return static_cast<long>(*v);
  }

  double real(std::string_view key) { return parse_real(expect(key, 1)[1]); }
  long integer(std::string_view key) { return parse_integer(expect(key, 1)[1]); }

  /// `key <count> <values...>`, count >= 1.
  Eigen::VectorXd vector(std::string_view key) {
    auto t = next(gp_quote(key));
    require(t.size() >= 2 && t[0] == key, where() + "expected '" + std::string(key) + " <count> <values>', got",
            gp_quote(line_));
    const long count = parse_integer(t[1]);
    require(count >= 1 && static_cast<std::size_t>(count) + 2 == t.size(),
            where() + "'" + std::string(key) + "' announces " + t[1] + " values, found", t.size() - 2);
    Eigen::VectorXd v(count);
    for (Eigen::Index i = 0; i < count; ++i) v(i) = parse_real(t[static_cast<std::size_t>(i) + 2]);
    return v;
  }

 private:
  std::istream& is_;
  long line_number_ = 0;
  std::string line_;
};

/// Reads one GP in the version-1 text format and factorises it; reads exactly up to and
/// including its `end` line, so that it can be embedded in a larger stream.
/// @throws std::invalid_argument naming the line and what was expected, on a truncated or
///         garbled input, another kernel type or an unsupported version; NumericalError.
template <Kernel K>
[[nodiscard]] GaussianProcess<K> read_gp_text_v1(std::istream& is) {
  using Gp = GaussianProcess<K>;
  GpTextV1Reader r{is};
  {
    const auto t = r.expect(kGpTextV1Magic, 1);
    require(t[1] == "1", r.where() + "unsupported format version (this reader reads 1), version", t[1]);
  }
  {
    const auto t = r.expect("kernel", 1);
    require(t[1] == K::kName,
            r.where() + "kernel type does not match this GaussianProcess (" + std::string(K::kName) + "), kernel",
            t[1]);
  }
  const Eigen::VectorXd theta = r.vector("log_parameters");
  const Eigen::VectorXd lower = r.vector("log_lower_bounds");
  const Eigen::VectorXd upper = r.vector("log_upper_bounds");
  typename Gp::State s{K::from_log_parameters(theta, lower, upper), {}, 0.0, 1.0, {}, {}};
  const long normalize = r.integer("normalize_y");
  require(normalize == 0 || normalize == 1, r.where() + "normalize_y must be 0 or 1", normalize);
  s.options.normalize_y = normalize == 1;
  s.y_mean = r.real("y_mean");
  s.y_std = r.real("y_std");
  require(s.y_std > 0.0, r.where() + "y_std must be > 0", s.y_std);
  s.options.initial_jitter = r.real("initial_jitter");
  const long attempts = r.integer("max_jitter_attempts");
  require(attempts >= 0 && attempts <= 30, r.where() + "max_jitter_attempts must be in [0, 30]", attempts);
  s.options.max_jitter_attempts = static_cast<int>(attempts);
  const long dimension = r.integer("dimension");
  const long samples = r.integer("samples");
  require(samples >= 0 && samples <= 100'000'000, r.where() + "samples must be in [0, 1e8]", samples);
  require(dimension >= (samples > 0 ? 1 : 0) && dimension <= 1'000'000,
          r.where() + "dimension must be in [1, 1e6] (0 allowed without samples)", dimension);
  // The announced sizes are not trusted for allocation: the dimension must be the kernel's,
  // and the samples are stored as their lines arrive (memory bounded by the input's size).
  require(dimension == 0 || s.kernel.accepts_dimension(static_cast<Eigen::Index>(dimension)),
          r.where() + "the kernel does not accept dimension", dimension);
  const auto n = static_cast<Eigen::Index>(samples);
  const auto dims = static_cast<Eigen::Index>(dimension);
  std::vector<double> values;  // row-major, dims + 1 per sample
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto tokens = r.next("sample " + std::to_string(i + 1) + " of " + std::to_string(n));
    require(static_cast<Eigen::Index>(tokens.size()) == dims + 1,
            r.where() + "a sample line needs " + std::to_string(dims + 1) + " numbers, found", tokens.size());
    for (const auto& token : tokens) values.push_back(r.parse_real(token));
  }
  r.expect("end", 1);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> rows(values.data(), n,
                                                                                                       dims + 1);
  s.inputs = rows.leftCols(dims);
  s.targets = rows.col(dims);
  return Gp::from_state(std::move(s));
}

}  // namespace adaptseg::detail
