#pragma once
/// @file
/// Fitted Gaussian processes as files: plain YAML, one key per quantity (kernel, log
/// hyperparameters and their bounds, options, target normalisation, training data), numbers
/// through the locale-independent codec of detail/number_text.hpp. The same mapping is what a
/// decision-model file holds for each of its GPs (decision_model.hpp). The GP itself
/// (gaussian_process.hpp, Eigen only) has no file format: it gives and takes its `State`.
///
/// Files of adaptseg 0.1's line format (`adaptseg.gaussian_process 1`) are no longer read (since
/// 0.2.0): load_gaussian_process says so.
///
/// @code
///   adaptseg::save_gaussian_process(gp, "o.yaml");
///   auto same = adaptseg::load_gaussian_process<adaptseg::ArdSquaredExponentialKernel>("o.yaml");
/// @endcode
/// The file of a model conditioned on three 1-D samples:
/// @code{.yaml}
///   format: adaptseg.gaussian_process/2
///   kernel: squared_exponential_ard
///   log_parameters: [0, -0.6931471805599453, -4.605170185988091]
///   log_lower_bounds: [-11.512925464970229, -11.512925464970229, -11.512925464970229]
///   log_upper_bounds: [11.512925464970229, 11.512925464970229, 11.512925464970229]
///   normalize_y: true
///   y_mean: 0
///   y_std: 1
///   initial_jitter: 1e-10
///   max_jitter_attempts: 8
///   inputs:
///     - [0]
///     - [0.5]
///     - [1]
///   targets: [0.1, 0.5, 0.1]
///   dimension: 1
/// @endcode

#include <adaptseg/core/gaussian_process.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <istream>
#include <iterator>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace adaptseg {

/// The `format` key of a standalone GP file.
inline constexpr std::string_view kGaussianProcessFormat = "adaptseg.gaussian_process/2";

namespace detail {

/// Emits the keys of a fitted GP into an open YAML mapping: kernel, hyperparameters with
/// bounds, options, normalisation, data (one input row per sample).
template <Kernel K>
void emit_gp_keys(YAML::Emitter& e, const GaussianProcess<K>& gp) {
  const auto s = gp.state();
  e << YAML::Key << "kernel" << YAML::Value << std::string(K::kName);
  e << YAML::Key << "log_parameters" << YAML::Value;
  emit_numbers(e, s.kernel.log_parameters());
  e << YAML::Key << "log_lower_bounds" << YAML::Value;
  emit_numbers(e, s.kernel.log_lower_bounds());
  e << YAML::Key << "log_upper_bounds" << YAML::Value;
  emit_numbers(e, s.kernel.log_upper_bounds());
  e << YAML::Key << "normalize_y" << YAML::Value << flag_text(s.options.normalize_y);
  e << YAML::Key << "y_mean" << YAML::Value;
  emit_number(e, s.y_mean);
  e << YAML::Key << "y_std" << YAML::Value;
  emit_number(e, s.y_std);
  e << YAML::Key << "initial_jitter" << YAML::Value;
  emit_number(e, s.options.initial_jitter);
  e << YAML::Key << "max_jitter_attempts" << YAML::Value << std::to_string(s.options.max_jitter_attempts);
  e << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
  for (Eigen::Index r = 0; r < s.inputs.rows(); ++r) emit_numbers(e, s.inputs.row(r).transpose());
  e << YAML::EndSeq;
  e << YAML::Key << "targets" << YAML::Value;
  emit_numbers(e, s.targets);
}

/// A fitted GP as one YAML mapping (the keys of emit_gp_keys).
template <Kernel K>
void emit_gp(YAML::Emitter& e, const GaussianProcess<K>& gp) {
  e << YAML::BeginMap;
  emit_gp_keys(e, gp);
  e << YAML::EndMap;
}

/// Reads what emit_gp_keys wrote. `dimension`: the number of inputs the caller needs (any
/// the kernel accepts if unset). Without samples (`allow_empty` only) the dimension is the
/// mapping's `dimension` key, 0 if absent; with samples, a `dimension` key must match their rows.
/// @throws std::invalid_argument naming the key; NumericalError if the data do not factorise.
template <Kernel K>
[[nodiscard]] GaussianProcess<K> read_gp(const YamlReader& r, std::optional<Eigen::Index> dimension,
                                         bool allow_empty = false) {
  const std::string kernel = r.text("kernel");
  if (kernel != K::kName)
    yaml_error(r.where(), "'" + r.path("kernel") + "' must be " + std::string(K::kName) + " (got '" + kernel + "')");
  const auto vec = [&](const char* key) {
    const auto v = r.numbers(key);
    return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
  };
  typename GaussianProcess<K>::State s{
      K::from_log_parameters(vec("log_parameters"), vec("log_lower_bounds"), vec("log_upper_bounds")),
      {},
      0.0,
      1.0,
      {},
      {}};
  s.options.normalize_y = r.flag("normalize_y");
  s.options.initial_jitter = r.number("initial_jitter");
  s.options.max_jitter_attempts = static_cast<int>(r.integer("max_jitter_attempts", 0, 30));
  s.y_mean = r.number("y_mean");
  s.y_std = r.number("y_std");
  s.targets = vec("targets");
  const YAML::Node rows = r.node("inputs");
  if (!rows.IsSequence() || rows.size() != static_cast<std::size_t>(s.targets.size()) ||
      (rows.size() == 0 && !allow_empty))
    yaml_error(r.where(), "'" + r.path("inputs") + "' must be a list of as many input rows as 'targets' has values" +
                              (allow_empty ? "" : " (>= 1)"));
  Eigen::Index dims = 0;
  // The `dimension` key, -1 if absent.
  const Eigen::Index announced =
      r.has("dimension") ? static_cast<Eigen::Index>(r.integer("dimension", 0, 1'000'000)) : Eigen::Index{-1};
  if (rows.size() > 0) {
    dims = rows[0].IsSequence() ? static_cast<Eigen::Index>(rows[0].size()) : 0;
    if (announced >= 0 && announced != dims)
      yaml_error(r.where(), "'" + r.path("dimension") + "' is " + std::to_string(announced) + " but the rows of '" +
                                r.path("inputs") + "' have " + std::to_string(dims) + " values");
  } else if (announced >= 0) {
    dims = announced;
  }
  if (dimension && dims != *dimension)
    yaml_error(r.where(), "'" + r.path("inputs") + "' rows must have " + std::to_string(*dimension) + " values");
  if ((rows.size() > 0 || dims > 0) && !s.kernel.accepts_dimension(dims))
    yaml_error(r.where(), "the kernel " + std::string(K::kName) + " does not accept inputs of dimension " +
                              std::to_string(dims) + " ('" + r.path("inputs") + "')");
  s.inputs.resize(static_cast<Eigen::Index>(rows.size()), dims);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].IsSequence() || static_cast<Eigen::Index>(rows[i].size()) != dims)
      yaml_error(r.where(), "'" + r.path("inputs") + "' rows must all have " + std::to_string(dims) + " values");
    for (Eigen::Index d = 0; d < dims; ++d)
      s.inputs(static_cast<Eigen::Index>(i), d) =
          r.number_of(rows[i][static_cast<std::size_t>(d)], r.path("inputs") + "[" + std::to_string(i) + "]");
  }
  return GaussianProcess<K>::from_state(std::move(s));
}

/// True if `text` starts (after blank and comment lines) with the header of adaptseg 0.1's GP
/// line format (`adaptseg.gaussian_process 1`), which is no longer read.
[[nodiscard]] inline bool is_gp_text_v1(const std::string& text) {
  constexpr std::string_view magic = "adaptseg.gaussian_process";
  std::istringstream is(text);
  std::string line;
  while (std::getline(is, line)) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string_view t = std::string_view(line).substr(first);
    return t.starts_with(magic) && t.size() > magic.size() && (t[magic.size()] == ' ' || t[magic.size()] == '\t');
  }
  return false;
}

}  // namespace detail

/// Writes `gp` as a YAML document (format in the file comment).
/// @throws std::invalid_argument if the stream fails.
template <Kernel K>
void save_gaussian_process(const GaussianProcess<K>& gp, std::ostream& os) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "format" << YAML::Value << std::string(kGaussianProcessFormat);
  detail::emit_gp_keys(e, gp);
  e << YAML::Key << "dimension" << YAML::Value << std::to_string(gp.dimension());
  e << YAML::EndMap;
  os << e.c_str() << '\n';
  detail::require(static_cast<bool>(os), "save_gaussian_process: output stream failed, good()", os.good());
}

/// Writes `gp` to `path` (created or truncated).
/// @throws std::invalid_argument if the file cannot be written.
template <Kernel K>
void save_gaussian_process(const GaussianProcess<K>& gp, const std::filesystem::path& path) {
  std::ofstream f(path);
  detail::require(static_cast<bool>(f), "save_gaussian_process: cannot open file for writing", path);
  save_gaussian_process(gp, f);
}

/// Reads a GP written by save_gaussian_process from the rest of `is`; `where` names the source
/// in errors.
/// @throws std::invalid_argument naming the source and the problem (not YAML, another format or
///         kernel, a missing or mistyped key, a truncated file, adaptseg 0.1's line format);
///         NumericalError.
template <Kernel K>
[[nodiscard]] GaussianProcess<K> load_gaussian_process(std::istream& is, const std::string& where = "<stream>") {
  const std::string text{std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>()};
  return detail::naming_file(where, [&] {
    if (detail::is_gp_text_v1(text))
      throw std::invalid_argument(where +
                                  ": a Gaussian process in adaptseg 0.1's line format is no longer read "
                                  "since adaptseg 0.2.0; fit it again and save it with save_gaussian_process");
    const detail::YamlReader r(detail::yaml_mapping(where, "a Gaussian process", [&] { return YAML::Load(text); }),
                               where);
    const std::string format = r.text("format");
    if (format != kGaussianProcessFormat)
      detail::yaml_error(where, "not an adaptseg Gaussian process (format must be " +
                                    std::string(kGaussianProcessFormat) + ", got '" + format + "')");
    return detail::read_gp<K>(r, std::nullopt, true);
  });
}

/// Reads a GP from `path` (see the stream overload).
/// @throws std::invalid_argument if the file cannot be opened or is malformed (the message
///         names the path); NumericalError.
template <Kernel K>
[[nodiscard]] GaussianProcess<K> load_gaussian_process(const std::filesystem::path& path) {
  std::ifstream f(path);
  detail::require(static_cast<bool>(f), "load_gaussian_process: cannot open file", path);
  return load_gaussian_process<K>(f, path.string());
}

}  // namespace adaptseg
