#pragma once
/// @file
/// The paper's decision function (§3.2.2-3.2.3; method.md §4): two Gaussian-process
/// regressions, O (altitude change → semantic-ratio change) and I (semantic-ratio change →
/// accuracy change), initialised on a training field and, for O, updated online.

#include <adaptseg/decision.hpp>
#include <adaptseg/error.hpp>
#include <adaptseg/gaussian_process.hpp>
#include <adaptseg/lawnmower_curve.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <istream>
#include <limits>
#include <optional>
#include <ostream>
#include <sstream>
#include <span>
#include <string>
#include <vector>

namespace adaptseg {

/// Decides whether to re-map a region from a lower altitude, and from which.
///
/// - O (paper Eq. `eq:veg2h`, left): a GP of Δσ = σ_{h_max} − σ_{h'} on the inputs
///   (Δh = h_max − h' [m], σ_{h_max}); the current image's σ is the only thing the UAV knows
///   when it decides, so it is an input (method.md §4). ARD squared-exponential kernel.
/// - I (Eq. `eq:veg2h`, right): a GP of ΔmIoU = mIoU_{h_max} − mIoU_{h'} on Δσ (the paper's,
///   GainInputs::delta_sigma), or on (Δσ, Δh) (GainInputs::delta_sigma_and_height, beyond the
///   paper: where the backend keeps σ nearly unchanged across altitudes, e.g. a ground-truth
///   oracle, Δσ alone predicts the same gain for every candidate altitude, so the cheapest
///   descent always looks best; Δh tells I how much finer the re-mapping is). Fixed after
///   initialisation (it needs ground truth). ARD kernel.
/// - Decision at σ, for each affordable candidate h' with exact extra time T(h'):
///   `ΔmIoU(h') = μ_I(μ_O(Δh', σ))`, gain `G = −ΔmIoU + κ·sd_I` (κ = `exploration`: optimism
///   under uncertainty), weighted if `weight_by_sigma` by the image's share of labels of
///   interest, σ · (valid fraction of the image) (field mIoU counts pixels: a region's errors
///   scale with its pixels of interest), utility `U = G / T`. Descend to the
///   candidate of largest U if σ >= `min_sigma`, G > 0 and U >= `min_utility`. With
///   `relative_utility` the threshold applies to U divided by the mean best utility of the
///   top-level images seen so far in this mission (current one included): a scale-free rule
///   that transfers between fields whose σ levels differ (a departure from the paper).
/// - Front-aware rule (`front_aware`, beyond the paper): the paper's utility ignores what
///   the UAV could have done instead. This rule compares with that alternative directly: the
///   field's lawnmowers at the top and candidate GSDs take times known from the geometry
///   (DecisionContext::lawnmowers) and reach about the training field's lawnmower mIoU at
///   the same GSD (`reference_lawnmower`), which gives a predicted lawnmower curve for the
///   field being flown. The mission's own end point is forecast as (elapsed + rest of the
///   top-level coverage, training mIoU at the top GSD + the field-level gains of the descents
///   taken so far), a region's field-level gain being its predicted gain G (unweighted) times
///   its share of the field's ground (DecisionContext::region_share), times σ / mean σ of the
///   top-level images so far if `weight_by_sigma`. The UAV descends to the candidate whose
///   forecast lies furthest above the predicted curve, if that is above the forecast without
///   descending (and σ >= `min_sigma`, U >= `min_utility` still apply): it descends while
///   descents beat flying lower everywhere, and stops when they no longer do.
/// - Online adaptation (§3.2.3): after a descent, (Δh', σ_{h_max}) → Δσ' joins O by an
///   O(n²) Cholesky extension; O's hyperparameters are re-optimised every `refit_every`
///   updates (0: never). `online = false` gives the paper's "non-adaptive" baseline.
///
/// @code
/// auto df = adaptseg::DecisionFunction::initialize(samples, {.min_sigma = 0.02});
/// adaptseg::Decision d = df.decide(context);   // context built by AdaptivePlanner
/// @endcode
class DecisionFunction {
 public:
  using OModel = GaussianProcess<ArdSquaredExponentialKernel>;
  using IModel = GaussianProcess<ArdSquaredExponentialKernel>;

  /// The inputs of I (see the class comment).
  enum class GainInputs {
    delta_sigma,             ///< ΔmIoU from Δσ (the paper's Eq. `eq:veg2h`)
    delta_sigma_and_height,  ///< ΔmIoU from (Δσ, Δh)
  };

  /// Thresholds and behaviour; validated by the constructor.
  struct Params {
    double min_sigma = 0.0;      ///< σ below which the UAV never descends
    double min_utility = 0.0;    ///< utility threshold [gain per second]
    double exploration = 0.0;    ///< κ >= 0, weight of I's predictive standard deviation
    bool weight_by_sigma = true; ///< gain weighted by σ (see class comment)
    bool online = true;          ///< update O after each descent (false: non-adaptive)
    int refit_every = 0;         ///< re-optimise O's hyperparameters every k updates (0: never)
    bool relative_utility = false;  ///< threshold on U / mean best U so far (see class comment)
    bool front_aware = false;    ///< descend only where the predicted front margin rises (see class comment)

    /// @throws std::invalid_argument naming the field.
    void validate() const {
      detail::require(std::isfinite(min_sigma) && min_sigma >= 0.0 && min_sigma <= 1.0,
                      "DecisionFunction::Params::min_sigma must be in [0, 1]", min_sigma);
      detail::require(std::isfinite(min_utility), "DecisionFunction::Params::min_utility must be finite",
                      min_utility);
      detail::require(std::isfinite(exploration) && exploration >= 0.0,
                      "DecisionFunction::Params::exploration must be finite and >= 0", exploration);
      detail::require(refit_every >= 0, "DecisionFunction::Params::refit_every must be >= 0", refit_every);
      detail::require(!(front_aware && relative_utility),
                      "DecisionFunction::Params: front_aware and relative_utility exclude each other; relative_utility",
                      relative_utility);
    }
  };

  /// @throws std::invalid_argument for invalid params or models of the wrong input
  ///         dimension (O: 2; I: 1 for GainInputs::delta_sigma, 2 for delta_sigma_and_height)
  ///         or without data.
  DecisionFunction(OModel o, IModel i, Params params) : o_(std::move(o)), i_(std::move(i)), params_(params) {
    params_.validate();
    detail::require(o_.size() > 0 && o_.dimension() == 2,
                    "DecisionFunction: O must hold data with 2 inputs (delta_h, sigma); dimension", o_.dimension());
    detail::require(i_.size() > 0 && (i_.dimension() == 1 || i_.dimension() == 2),
                    "DecisionFunction: I must hold data with 1 input (delta_sigma) or 2 (delta_sigma, delta_h); "
                    "dimension",
                    i_.dimension());
  }

  /// Fits O and I to initialisation samples (hyperparameters by maximum marginal likelihood,
  /// `restarts` deterministic restarts from `seed`).
  /// @throws std::invalid_argument if there is no sample or a sample is not finite;
  ///         NumericalError if a GP cannot be factorised.
  [[nodiscard]] static DecisionFunction initialize(std::span<const RegionSample> samples, Params params,
                                                   int restarts = 3, std::uint64_t seed = 0,
                                                   GainInputs gain_inputs = GainInputs::delta_sigma) {
    detail::require(!samples.empty(), "DecisionFunction::initialize: number of samples must be > 0", 0);
    const auto n = static_cast<Eigen::Index>(samples.size());
    const bool by_height = gain_inputs == GainInputs::delta_sigma_and_height;
    Eigen::MatrixXd xo(n, 2), xi(n, by_height ? 2 : 1);
    Eigen::VectorXd yo(n), yi(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const RegionSample& s = samples[static_cast<std::size_t>(k)];
      xo(k, 0) = s.delta_h_m;
      xo(k, 1) = s.sigma_top;
      yo(k) = s.delta_sigma();
      xi(k, 0) = s.delta_sigma();
      if (by_height) xi(k, 1) = s.delta_h_m;
      yi(k) = s.delta_miou();
    }
    ArdSquaredExponentialKernel::Bounds ob;
    ob.length_scale = {1e-2, 1e3};
    ob.signal_variance = {1e-4, 1e2};
    ob.noise_variance = {1e-8, 1e1};
    ArdSquaredExponentialKernel::Bounds ib;
    ib.length_scale = {1e-3, 1e2};
    ib.signal_variance = {1e-4, 1e2};
    ib.noise_variance = {1e-8, 1e1};
    const auto spread = [](const Eigen::VectorXd& v) {
      const double sd = std::sqrt((v.array() - v.mean()).square().mean());
      return std::clamp(sd, 1e-2, 1e2);
    };
    OModel o(ArdSquaredExponentialKernel(Eigen::Vector2d(spread(xo.col(0)), spread(xo.col(1))), 1.0, 0.1, ob),
             {.normalize_y = true});
    Eigen::VectorXd il(xi.cols());
    il(0) = std::clamp(spread(xi.col(0)), 1e-3, 1e2);
    if (by_height) il(1) = spread(xi.col(1));
    IModel i(ArdSquaredExponentialKernel(il, 1.0, 0.1, ib), {.normalize_y = true});
    (void)o.fit(xo, yo, {.restarts = restarts, .seed = seed});
    (void)i.fit(xi, yi, {.restarts = restarts, .seed = seed + 1});
    return DecisionFunction(std::move(o), std::move(i), params);
  }

  [[nodiscard]] std::string name() const { return params_.online ? "adaptive" : "nonadaptive"; }
  [[nodiscard]] const Params& params() const noexcept { return params_; }
  /// Replaces the thresholds (e.g. after calibration).
  /// @throws std::invalid_argument for invalid params.
  void set_params(const Params& p) {
    p.validate();
    params_ = p;
  }
  [[nodiscard]] const OModel& o_model() const noexcept { return o_; }
  [[nodiscard]] const IModel& i_model() const noexcept { return i_; }
  /// What I predicts from (its input dimension).
  [[nodiscard]] GainInputs gain_inputs() const noexcept {
    return i_.dimension() == 2 ? GainInputs::delta_sigma_and_height : GainInputs::delta_sigma;
  }
  [[nodiscard]] int online_updates() const noexcept { return updates_; }

  /// The training field's lawnmower mIoU by GSD, the front-aware rule's expectation of what a
  /// lawnmower reaches on the field being flown (see the class comment).
  /// @throws std::invalid_argument for non-finite values or a GSD <= 0.
  void set_reference_lawnmower(std::vector<GsdPoint> points) {
    for (const auto& p : points)
      detail::require(std::isfinite(p.gsd_cm) && p.gsd_cm > 0.0 && std::isfinite(p.miou),
                      "DecisionFunction::set_reference_lawnmower: GSD must be > 0 and mIoU finite; GSD", p.gsd_cm);
    reference_ = std::move(points);
  }
  [[nodiscard]] const std::vector<GsdPoint>& reference_lawnmower() const noexcept { return reference_; }

  /// Predicted Δσ, ΔmIoU and its standard deviation, gain and utility of one candidate.
  [[nodiscard]] CandidateScore score(const DecisionContext& ctx, const Candidate& c) const {
    const double sigma = ctx.sigma;
    CandidateScore s;
    s.gsd_cm = c.gsd_cm;
    const double delta_h = ctx.top_altitude_m - c.altitude_m;
    s.predicted_delta_sigma = o_.predict_mean(Eigen::RowVector2d(delta_h, sigma))(0);
    Eigen::MatrixXd qi(1, i_.dimension());
    qi(0, 0) = s.predicted_delta_sigma;
    if (qi.cols() == 2) qi(0, 1) = delta_h;
    const auto p = i_.predict(qi);
    s.predicted_delta_miou = p.mean(0);
    s.predicted_delta_miou_std = std::sqrt(std::max(0.0, p.variance(0)));
    const double gain = gain_of(s, ctx);
    s.utility = c.extra_time_s > 0.0 ? gain / c.extra_time_s : (gain > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
    return s;
  }

  /// The decision at a top-level waypoint (see the class comment).
  /// @throws std::invalid_argument with `front_aware` if the context has no lawnmower
  ///         forecasts or the model no reference lawnmower.
  [[nodiscard]] Decision decide(const DecisionContext& c) {
    if (params_.front_aware) return decide_front_aware(c);
    Decision d;
    double best = -std::numeric_limits<double>::infinity();
    std::size_t best_index = 0;
    for (std::size_t k = 0; k < c.candidates.size(); ++k) {
      d.scores.push_back(score(c, c.candidates[k]));
      const CandidateScore& s = d.scores.back();
      if (gain_of(s, c) > 0.0 && s.utility > best) {
        best = s.utility;
        best_index = k;
      }
    }
    if (!std::isfinite(best)) return d;
    double u = best;
    if (params_.relative_utility) {
      utility_sum_ += best;
      ++utility_count_;
      const double mean = utility_sum_ / static_cast<double>(utility_count_);
      u = mean > 0.0 ? best / mean : 0.0;
    }
    if (c.sigma >= params_.min_sigma && u >= params_.min_utility) {
      d.descend = true;
      d.gsd_cm = c.candidates[best_index].gsd_cm;
    }
    return d;
  }

  /// Forgets the per-mission state (the running mean of `relative_utility`); call between
  /// missions when reusing one object.
  void reset_mission() noexcept {
    utility_sum_ = 0.0;
    utility_count_ = 0;
    sigma_sum_ = 0.0;
    sigma_count_ = 0;
    forecast_miou_.reset();
  }

  /// Online update of O after a descent (no-op unless `online`).
  void observe(const DescentOutcome& out) {
    if (!params_.online) return;
    o_.add_observation(Eigen::Vector2d(out.top_altitude_m - out.sub_altitude_m, out.sigma_top),
                       out.sigma_top - out.sigma_sub);
    ++updates_;
    if (params_.refit_every > 0 && updates_ % params_.refit_every == 0)
      (void)o_.refit({.restarts = 1, .seed = static_cast<std::uint64_t>(updates_)});
  }

  /// Writes params, O and I as text (embeddable; read back by `load`).
  void save(std::ostream& os) const {
    os << "adaptseg.decision_function 3\n";
    os << "min_sigma " << fmt(params_.min_sigma) << "\nmin_utility " << fmt(params_.min_utility)
       << "\nexploration " << fmt(params_.exploration) << "\nweight_by_sigma " << params_.weight_by_sigma
       << "\nonline " << params_.online << "\nrefit_every " << params_.refit_every
       << "\nrelative_utility " << params_.relative_utility << "\nfront_aware " << params_.front_aware
       << "\nreference_lawnmower " << reference_.size();
    for (const auto& p : reference_) os << ' ' << fmt(p.gsd_cm) << ' ' << fmt(p.miou);
    os << '\n';
    o_.save(os);
    i_.save(os);
    os << "end adaptseg.decision_function\n";
    detail::require(static_cast<bool>(os), "DecisionFunction::save: output stream failed, good()", os.good());
  }

  /// Reads what `save` wrote.
  /// @throws std::invalid_argument naming what is wrong for truncated or garbled input.
  [[nodiscard]] static DecisionFunction load(std::istream& is) {
    const auto token = [&](const std::string& what) {
      std::string t;
      detail::require(static_cast<bool>(is >> t), "DecisionFunction::load: input ends before " + what, "<end of input>");
      return t;
    };
    const auto expect = [&](const std::string& key) {
      const std::string t = token("'" + key + "'");
      detail::require(t == key, "DecisionFunction::load: expected '" + key + "', found", t);
    };
    const auto parse = [&](const std::string& t, const std::string& what) {
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(t, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      detail::require(used == t.size() && std::isfinite(v), "DecisionFunction::load: bad number for " + what, t);
      return v;
    };
    const auto number = [&](const std::string& key) {
      expect(key);
      return parse(token("the value of '" + key + "'"), "'" + key + "'");
    };
    expect("adaptseg.decision_function");
    const std::string version = token("the format version");
    detail::require(version == "1" || version == "2" || version == "3",
                    "DecisionFunction::load: unsupported format version", version);
    Params p;
    p.min_sigma = number("min_sigma");
    p.min_utility = number("min_utility");
    p.exploration = number("exploration");
    p.weight_by_sigma = number("weight_by_sigma") != 0.0;
    p.online = number("online") != 0.0;
    const double refit_every = number("refit_every");  // range-checked before the cast (UB otherwise)
    detail::require(refit_every >= 0.0 && refit_every <= 1e9 && refit_every == std::floor(refit_every),
                    "DecisionFunction::load: refit_every must be an integer in [0, 1e9]", refit_every);
    p.refit_every = static_cast<int>(refit_every);
    p.relative_utility = number("relative_utility") != 0.0;
    std::vector<GsdPoint> reference;
    if (version != "1") {  // version 1 had neither
      p.front_aware = number("front_aware") != 0.0;
      const double n = number("reference_lawnmower");
      detail::require(n >= 0.0 && n <= 1000.0 && n == std::floor(n),
                      "DecisionFunction::load: bad point count for 'reference_lawnmower'", n);
      const auto value = [&](const char* what) {
        const std::string name = std::string("a reference_lawnmower ") + what;
        return parse(token(name), name);
      };
      for (int k = 0; k < static_cast<int>(n); ++k) {
        const double g = value("GSD");
        reference.push_back({g, value("mIoU")});
      }
    }
    is >> std::ws;
    OModel o = OModel::load(is);
    is >> std::ws;
    IModel i = version == "3" ? IModel::load(is) : load_isotropic_i(is);
    expect("end");
    expect("adaptseg.decision_function");
    DecisionFunction df(std::move(o), std::move(i), p);
    df.set_reference_lawnmower(std::move(reference));
    return df;
  }

 private:
  /// Versions 1-2 stored I with the isotropic kernel, which for its one input is the ARD
  /// kernel with one length scale (same parameters, same layout): the block is read up to its
  /// `end` line and parsed as that.
  static IModel load_isotropic_i(std::istream& is) {
    std::string block, line;
    bool ended = false;
    while (std::getline(is, line)) {
      if (line == "kernel " + std::string(SquaredExponentialKernel::kName))
        line = "kernel " + std::string(ArdSquaredExponentialKernel::kName);
      block += line + '\n';
      if (line.rfind("end ", 0) == 0) {
        ended = true;
        break;
      }
    }
    detail::require(ended, "DecisionFunction::load: input ends inside I's Gaussian process", "<end of input>");
    std::istringstream in(block);
    IModel i = IModel::load(in);
    detail::require(i.dimension() == 1, "DecisionFunction::load: I of a version 1-2 file must have 1 input; dimension",
                    i.dimension());
    return i;
  }

  /// The front-aware rule (see the class comment).
  [[nodiscard]] Decision decide_front_aware(const DecisionContext& c) {
    detail::require(!c.lawnmowers.empty(),
                    "DecisionFunction::decide: front_aware needs the context's lawnmower forecasts; count",
                    c.lawnmowers.size());
    detail::require(!reference_.empty(),
                    "DecisionFunction::decide: front_aware needs a reference lawnmower (set_reference_lawnmower); count",
                    reference_.size());
    std::vector<CurvePoint> curve;
    for (const auto& f : c.lawnmowers) curve.push_back({f.time_s, miou_at_gsd(reference_, f.gsd_cm)});
    if (!forecast_miou_) forecast_miou_ = miou_at_gsd(reference_, c.top_gsd_cm);
    sigma_sum_ += c.sigma;
    ++sigma_count_;
    const double mean_sigma = sigma_sum_ / static_cast<double>(sigma_count_);
    const double weight = c.region_share * (params_.weight_by_sigma && mean_sigma > 0.0 ? c.sigma / mean_sigma : 1.0);
    const double t_end = c.elapsed_s + c.rest_s;
    const double stay = front_margin(curve, t_end, *forecast_miou_);

    Decision d;
    double best = stay;
    std::optional<std::size_t> best_index;
    std::vector<double> field_gain;
    for (std::size_t k = 0; k < c.candidates.size(); ++k) {
      CandidateScore s = score(c, c.candidates[k]);
      const double g = unweighted_gain(s);
      field_gain.push_back(g * weight);
      s.predicted_front_margin =
          front_margin(curve, t_end + c.candidates[k].extra_time_s, *forecast_miou_ + field_gain.back());
      if (g > 0.0 && s.utility >= params_.min_utility && s.predicted_front_margin > best) {
        best = s.predicted_front_margin;
        best_index = k;
      }
      d.scores.push_back(s);
    }
    if (best_index && c.sigma >= params_.min_sigma) {
      d.descend = true;
      d.gsd_cm = c.candidates[*best_index].gsd_cm;
      *forecast_miou_ += field_gain[*best_index];
    }
    return d;
  }

  /// G = −ΔmIoU + κ·sd_I (see the class comment).
  [[nodiscard]] double unweighted_gain(const CandidateScore& s) const {
    return -s.predicted_delta_miou + params_.exploration * s.predicted_delta_miou_std;
  }
  /// G, weighted by σ · valid fraction if `weight_by_sigma` (the paper's rule).
  [[nodiscard]] double gain_of(const CandidateScore& s, const DecisionContext& c) const {
    const double g = unweighted_gain(s);
    return params_.weight_by_sigma ? g * c.sigma * c.valid_fraction : g;
  }
  static std::string fmt(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
  }

  OModel o_;
  IModel i_;
  Params params_;
  int updates_ = 0;
  double utility_sum_ = 0.0;
  std::size_t utility_count_ = 0;
  std::vector<GsdPoint> reference_;        ///< training lawnmower mIoU by GSD (front-aware rule)
  double sigma_sum_ = 0.0;                 ///< σ of this mission's top-level images (front-aware rule)
  std::size_t sigma_count_ = 0;
  std::optional<double> forecast_miou_;    ///< this mission's forecast end mIoU (front-aware rule)
};

static_assert(DecisionPolicy<DecisionFunction>);

}  // namespace adaptseg
