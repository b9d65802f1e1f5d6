#pragma once
/// @file
/// The front-aware rule (FrontAwarePolicy, core/front_aware_policy.hpp) beyond deciding: its
/// name, its keys in the model file's `rule` mapping and its calibration search (its settings
/// chosen on the training fields, each flown with a model fitted without it:
/// front_aware_search.hpp). One entry of DecisionRules (decision_rules.hpp); docs/method.md,
/// "The front-aware rule".

#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>
#include <adaptseg/vision/front_aware_search.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// The front-aware rule in the model file and in calibration.
struct FrontAwareRule {
  using Policy = FrontAwarePolicy;
  /// Its name: `kind` in the model file, `--rule` of the programs, CalibrationOptions::rule.
  static constexpr std::string_view kName = "front-aware";

  /// Writes the rule's own keys into the open `rule` mapping (after `kind`, `online` and
  /// `min_sigma`, which every rule has).
  static void write_keys(YAML::Emitter& e, const FrontAwarePolicy& rule) {
    using detail::emit_numbers;
    const auto num = [](double v) { return detail::format_number(v); };
    const FrontAwarePolicy::Params& p = rule.params();
    e << YAML::Key << "confidence" << YAML::Value << num(p.confidence);
    e << YAML::Key << "scale_prior_sd" << YAML::Value << num(p.scale_prior_sd);
    e << YAML::Key << "sigma_prior_weight" << YAML::Value << num(p.sigma_prior_weight);
    e << YAML::Key << "sigma_prior_sd" << YAML::Value << num(p.sigma_prior_sd);
    // The curve source as the flags of earlier versions, so that their files keep their bytes.
    if (p.curve != CurveSource::training) e << YAML::Key << "field_curve" << YAML::Value << detail::flag_text(true);
    if (p.curve == CurveSource::corrected || p.curve == CurveSource::mixture)
      e << YAML::Key << "curve_ratio" << YAML::Value << detail::flag_text(true);
    if (p.curve == CurveSource::mixture) e << YAML::Key << "curve_mixture" << YAML::Value << detail::flag_text(true);
    if (p.top_level != TopLevelChoice::undominated)
      e << YAML::Key << "top_level" << YAML::Value << to_string(p.top_level);
    if (p.curve_agreement > 0.0) e << YAML::Key << "curve_agreement" << YAML::Value << num(p.curve_agreement);
    if (p.finest_descent_gsd_cm > 0.0)
      e << YAML::Key << "finest_descent_gsd_cm" << YAML::Value << num(p.finest_descent_gsd_cm);
    if (p.longest_descent_s > 0.0) e << YAML::Key << "longest_descent_s" << YAML::Value << num(p.longest_descent_s);
    if (std::isfinite(p.jump_bound)) e << YAML::Key << "jump_bound" << YAML::Value << num(p.jump_bound);
    if (p.field_factor != FieldFactorSource::scene_check)
      e << YAML::Key << "field_factor" << YAML::Value << to_string(p.field_factor);
    if (p.relabel_transfer != 1.0) e << YAML::Key << "relabel_transfer" << YAML::Value << num(p.relabel_transfer);
    if (p.relabel_region_sd > 0.0) e << YAML::Key << "relabel_region_sd" << YAML::Value << num(p.relabel_region_sd);
    if (p.relabel_field_sd > 0.0) e << YAML::Key << "relabel_field_sd" << YAML::Value << num(p.relabel_field_sd);
    if (p.learn_stop_only) e << YAML::Key << "learn_stop_only" << YAML::Value << detail::flag_text(true);
    std::vector<std::pair<double, double>> ratios, biases;
    for (const GainRatio& x : p.gain_ratios) ratios.emplace_back(x.gsd_cm, x.ratio);
    for (const MarginBias& x : p.margin_biases) biases.emplace_back(x.gsd_cm, x.per_s);
    write_pairs(e, "gain_ratio_gsd_cm", "gain_ratio", ratios);
    write_pairs(e, "margin_bias_gsd_cm", "margin_bias_per_s", biases);
    e << YAML::Key << "reference" << YAML::Value << YAML::BeginSeq;
    for (const auto& r : rule.reference()) {
      std::vector<double> g, m;
      for (const auto& pt : r.points) g.push_back(pt.gsd_cm), m.push_back(pt.miou);
      e << YAML::BeginMap << YAML::Key << "field" << YAML::Value << r.field << YAML::Key << "field_sigma" << YAML::Value
        << num(r.field_sigma);
      if (r.field_input > 0.0) e << YAML::Key << "field_input" << YAML::Value << num(r.field_input);
      if (!r.top_inputs.empty()) {
        std::vector<double> tg, tx;
        for (const auto& [gsd, x] : r.top_inputs) tg.push_back(gsd), tx.push_back(x);
        e << YAML::Key << "top_input_gsd_cm" << YAML::Value;
        emit_numbers(e, tg);
        e << YAML::Key << "top_input" << YAML::Value;
        emit_numbers(e, tx);
      }
      e << YAML::Key << "gsd_cm" << YAML::Value;
      emit_numbers(e, g);
      e << YAML::Key << "miou" << YAML::Value;
      emit_numbers(e, m);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }

  /// Reads what write_keys wrote: the rule over `model` with the keys every rule has.
  /// @throws std::invalid_argument naming the file and the key.
  [[nodiscard]] static FrontAwarePolicy read_keys(const detail::YamlReader& rule, GainModel model, double min_sigma,
                                                  bool online) {
    const YAML::Node refs = rule.node("reference");
    if (!refs.IsSequence()) detail::yaml_error(rule.where(), "'rule.reference' must be a list of curves");
    std::vector<ReferenceCurve> reference;
    for (std::size_t k = 0; k < refs.size(); ++k) {
      if (!refs[k].IsMap()) detail::yaml_error(rule.where(), "'rule.reference' entries must be mappings");
      const detail::YamlReader c(refs[k], rule.where());
      const auto g = c.numbers("gsd_cm");
      const auto v = c.numbers("miou");
      if (g.size() != v.size())
        detail::yaml_error(rule.where(), "a 'rule.reference' curve needs as many 'miou' as 'gsd_cm' values");
      ReferenceCurve curve{c.text("field"),
                           {},
                           c.has("field_sigma") ? c.number("field_sigma") : 0.0,
                           c.has("field_input") ? c.number("field_input") : 0.0};
      for (std::size_t i = 0; i < g.size(); ++i) curve.points.push_back({g[i], v[i]});
      if (c.has("top_input_gsd_cm") || c.has("top_input")) {
        const auto tg = c.numbers("top_input_gsd_cm");
        const auto tx = c.numbers("top_input");
        if (tg.size() != tx.size())
          detail::yaml_error(rule.where(),
                             "a 'rule.reference' curve needs as many 'top_input' as 'top_input_gsd_cm' values");
        for (std::size_t i = 0; i < tg.size(); ++i) curve.top_inputs.emplace_back(tg[i], tx[i]);
      }
      reference.push_back(std::move(curve));
    }
    return FrontAwarePolicy(
        std::move(model), std::move(reference),
        {.min_sigma = min_sigma,
         .online = online,
         .confidence = rule.number("confidence"),
         .scale_prior_sd = rule.number("scale_prior_sd"),
         .sigma_prior_weight = rule.number("sigma_prior_weight"),
         .sigma_prior_sd = rule.has("sigma_prior_sd") ? rule.number("sigma_prior_sd") : 0.0,
         .curve_agreement = rule.has("curve_agreement") ? rule.number("curve_agreement") : 0.0,
         .finest_descent_gsd_cm = rule.has("finest_descent_gsd_cm") ? rule.number("finest_descent_gsd_cm") : 0.0,
         .longest_descent_s = rule.has("longest_descent_s") ? rule.number("longest_descent_s") : 0.0,
         .jump_bound = rule.has("jump_bound") ? rule.number("jump_bound") : std::numeric_limits<double>::infinity(),
         .curve = read_curve(rule),
         .top_level =
             rule.has("top_level") ? read_named(rule, "top_level", kTopLevelChoices) : TopLevelChoice::undominated,
         .field_factor = rule.has("field_factor") ? read_named(rule, "field_factor", kFieldFactorSources)
                                                  : FieldFactorSource::scene_check,
         .relabel_transfer = rule.has("relabel_transfer") ? rule.number("relabel_transfer") : 1.0,
         .relabel_region_sd = rule.has("relabel_region_sd") ? rule.number("relabel_region_sd") : 0.0,
         .relabel_field_sd = rule.has("relabel_field_sd") ? rule.number("relabel_field_sd") : 0.0,
         .learn_stop_only = rule.has("learn_stop_only") && rule.flag("learn_stop_only"),
         .gain_ratios = read_gain_ratios(rule),
         .margin_biases = read_margin_biases(rule)});
  }

  /// Per descent GSD, what the folds measured (FrontAwarePolicy::Params `gain_ratios` and
  /// `margin_biases`): keys `gsd_key` and `value_key`, two lists of one length; none: nothing
  /// written (files without them keep their bytes).
  static void write_pairs(YAML::Emitter& e, const char* gsd_key, const char* value_key,
                          const std::vector<std::pair<double, double>>& pairs) {
    if (pairs.empty()) return;
    std::vector<double> g, v;
    for (const auto& [gsd, value] : pairs) g.push_back(gsd), v.push_back(value);
    e << YAML::Key << gsd_key << YAML::Value;
    detail::emit_numbers(e, g);
    e << YAML::Key << value_key << YAML::Value;
    detail::emit_numbers(e, v);
  }

  /// What write_pairs wrote (absent both keys: none).
  /// @throws std::invalid_argument naming the file and the keys for lists of two lengths.
  [[nodiscard]] static std::vector<std::pair<double, double>> read_pairs(const detail::YamlReader& rule,
                                                                         const char* gsd_key, const char* value_key) {
    if (!rule.has(gsd_key) && !rule.has(value_key)) return {};
    const auto g = rule.numbers(gsd_key);
    const auto v = rule.numbers(value_key);
    if (g.size() != v.size())
      detail::yaml_error(rule.where(),
                         std::string("'rule.") + value_key + "' needs as many values as 'rule." + gsd_key + "'");
    std::vector<std::pair<double, double>> out;
    for (std::size_t i = 0; i < g.size(); ++i) out.emplace_back(g[i], v[i]);
    return out;
  }

  /// `rule.gain_ratio_gsd_cm` and `rule.gain_ratio` (absent: none).
  [[nodiscard]] static std::vector<GainRatio> read_gain_ratios(const detail::YamlReader& rule) {
    std::vector<GainRatio> out;
    for (const auto& [g, r] : read_pairs(rule, "gain_ratio_gsd_cm", "gain_ratio")) out.push_back({g, r});
    return out;
  }

  /// `rule.margin_bias_gsd_cm` and `rule.margin_bias_per_s` (absent: none).
  [[nodiscard]] static std::vector<MarginBias> read_margin_biases(const detail::YamlReader& rule) {
    std::vector<MarginBias> out;
    for (const auto& [g, b] : read_pairs(rule, "margin_bias_gsd_cm", "margin_bias_per_s")) out.push_back({g, b});
    return out;
  }

  /// The curve source of the flags `field_curve`, `curve_ratio` and `curve_mixture` (absent:
  /// false; the ratio alone, which earlier versions ignored, reads the training fields' curves as
  /// they did; the mixture only with both).
  [[nodiscard]] static CurveSource read_curve(const detail::YamlReader& rule) {
    const auto set = [&](const char* key) { return rule.has(key) && rule.flag(key); };
    if (!set("field_curve")) return CurveSource::training;
    if (!set("curve_ratio")) return CurveSource::field;
    return set("curve_mixture") ? CurveSource::mixture : CurveSource::corrected;
  }

  /// The value under `key` of `rule`, one of `table`'s names (a TopLevelChoice, a
  /// FieldFactorSource); elsewhere an error naming the file and the names it may be.
  template <typename Enum, std::size_t N>
  [[nodiscard]] static Enum read_named(const detail::YamlReader& rule, const char* key,
                                       const std::array<detail::NamedValue<Enum>, N>& table) {
    const std::string name = rule.text(key);
    std::string allowed;
    for (std::size_t k = 0; k < N; ++k) {
      if (k > 0) allowed += k + 1 == N ? " or " : ", ";
      allowed += table[k].name;
      if (name == table[k].name) return table[k].value;
    }
    detail::yaml_error(rule.where(), "'rule." + std::string(key) + "' must be " + allowed + " (got '" + name + "')");
  }

  /// Refuses options its search cannot use (before calibrate() samples anything).
  /// @throws std::invalid_argument if `confidences` or `slope_poolings` is empty,
  ///         `slope_poolings`, `top_levels`, `finest_descent_gsd_cm` or `longest_descent_s` names
  ///         a value twice, `finest_descent_gsd_cm` or `longest_descent_s` holds a negative or
  ///         non-finite limit, `field_grounds` names a
  ///         ground that is not the first field of its own, or `relabel_transfer`,
  ///         `relabel_region_spread` or `relabel_field_spread` is asked without the relabelled
  ///         field factor.
  static void check_options(const CalibrationOptions& options) {
    detail::require(!options.confidences.empty(), "calibrate: confidences must not be empty", 0);
    detail::require(!options.slope_poolings.empty(), "calibrate: slope_poolings must not be empty", 0);
    for (std::size_t k = 0; k < options.slope_poolings.size(); ++k)
      for (std::size_t j = 0; j < k; ++j)
        detail::require(options.slope_poolings[j] != options.slope_poolings[k],
                        "calibrate: slope_poolings names a pooling twice:", to_string(options.slope_poolings[k]));
    for (std::size_t k = 0; k < options.top_levels.size(); ++k)
      for (std::size_t j = 0; j < k; ++j)
        detail::require(options.top_levels[j] != options.top_levels[k],
                        "calibrate: top_levels names a choice twice:", to_string(options.top_levels[k]));
    const auto check_limits = [](const std::vector<double>& limits, const char* name, const char* what) {
      for (std::size_t k = 0; k < limits.size(); ++k) {
        detail::require(std::isfinite(limits[k]) && limits[k] >= 0.0,
                        "calibrate: " + std::string(name) + " must hold finite " + what + " >= 0 (0: no limit); got",
                        limits[k]);
        for (std::size_t j = 0; j < k; ++j)
          detail::require(limits[j] != limits[k],
                          "calibrate: " + std::string(name) + " names a limit twice:", limits[k]);
      }
    };
    check_limits(options.finest_descent_gsd_cm, "finest_descent_gsd_cm", "GSDs");
    check_limits(options.longest_descent_s, "longest_descent_s", "seconds");
    for (std::size_t k = 0; k < options.field_grounds.size(); ++k)
      detail::require(
          options.field_grounds[k] <= k && options.field_grounds[options.field_grounds[k]] == options.field_grounds[k],
          "calibrate: field_grounds[k] must name the first field of k's ground (<= k, its own ground "
          "itself); at k =",
          k);
    detail::require(!options.relabel_transfer || options.front_aware.field_factor == FieldFactorSource::relabelled,
                    "calibrate: relabel_transfer (how far the gain follows the relabelled share) needs the field "
                    "factor 'relabelled'; the field factor",
                    to_string(options.front_aware.field_factor));
    detail::require(!options.relabel_region_spread || options.front_aware.field_factor == FieldFactorSource::relabelled,
                    "calibrate: relabel_region_spread (how far a region's relabelled share strays from its field's) "
                    "needs the field factor 'relabelled'; the field factor",
                    to_string(options.front_aware.field_factor));
    detail::require(!options.relabel_field_spread || options.front_aware.field_factor == FieldFactorSource::relabelled,
                    "calibrate: relabel_field_spread (how far the fields' relabelled shares stray from the forecast) "
                    "needs the field factor 'relabelled'; the field factor",
                    to_string(options.front_aware.field_factor));
  }

  /// The calibration search (CalibrationOptions: `front_aware`, `confidences`,
  /// `slope_poolings`, `top_levels`, `sigma_prior`): `min_sigma` and the σ̂ prior's settings as
  /// given (with several fields `scale_prior_sd` is estimated from their spread instead, and the
  /// prior as `sigma_prior` says); z chosen among `confidences` by the mean front margin over
  /// the training fields, each flown with a model fitted without it (one field: the field and
  /// its halves, with the model of the whole field), ties to the larger z; with ranked cells
  /// and several fields this for each of `slope_poolings`, and the first pooling kept unless
  /// another beats it by more than the folds' noise (detail::select_pooling); with ranked cells
  /// all that for each of `top_levels`, the first kept unless another beats it by more than
  /// the folds' noise (detail::choose_setting; front_aware_search.hpp); with several
  /// `finest_descent_gsd_cm`, every setting flown with the first and the setting kept then
  /// flown with each other one, the first kept unless another beats it by more than the folds'
  /// noise (detail::choose_finest_descent). `fly(field, policy, curve,
  /// margin)` flies an adaptive mission of `policy` and scores it against `curve`
  /// (detail::fly_scored).
  /// @throws std::invalid_argument as check_options.
  template <class Fly>
  [[nodiscard]] static RuleSearchResult search(const RuleSearchInputs& in, Fly&& fly) {
    check_options(in.options);
    return search_front_aware(in, std::forward<Fly>(fly));
  }
};

}  // namespace adaptseg
