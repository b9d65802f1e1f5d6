#pragma once
/// @file
/// What re-mapping chosen cells of a region gains, forecast from one decision input of the
/// top-level image (beyond the paper; docs/method.md, "Cells that pay"): the cell gain model,
/// fitted to calibration samples of single cells re-mapped alone (the scores its input is chosen
/// by on the training fields: cell_input_scores.hpp).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/detail/field_slopes.hpp>
#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/detail/interpolate.hpp>
#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/error.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// How the cell gain model's slopes β and α pool the training fields (CellGainModel::fit):
/// - `cells`: one weighted least-squares fit over every field's cells together. A field weighs
///   by its cells' Σ w·x², so the field where the input is largest sets the slope, whether or not
///   the other fields agree (docs/method.md, "Cells that pay", has a bundled case).
/// - `fields`: each field's own slope, pooled as random effects (DerSimonian and Laird 1986):
///   by the fields' precision where they agree within their cells' scatter, alike where they
///   disagree beyond it. A new field is one more field, not more cells of the training fields'.
/// - `field-entropy`: as `fields`, with β a linear function of the field's mean top-level
///   entropy (a random-effects meta-regression): how unsure the network is of the whole field,
///   which on ground it never trained on marks how much a closer look gains. In flight the
///   field's entropy is estimated from the top-level images so far (FrontAwarePolicy).
/// Which one a model uses is a calibration choice (CalibrationOptions::slope_poolings, chosen
/// with the confidence level z by leave-one-field-out); docs/method.md, "Cells that pay".
enum class SlopePooling { cells, fields, field_entropy };

/// Every pooling by name (`slope_pooling` in the model file, `--slope-pooling` of the programs).
inline constexpr std::array<detail::NamedValue<SlopePooling>, 3> kSlopePoolings{{
    {SlopePooling::cells, "cells"},
    {SlopePooling::fields, "fields"},
    {SlopePooling::field_entropy, "field-entropy"},
}};

/// The name of a pooling.
[[nodiscard]] inline std::string to_string(SlopePooling p) {
  return detail::name_of(kSlopePoolings, p, "slope pooling");
}

/// Parses a pooling's name.
/// @throws std::invalid_argument for anything but `cells`, `fields` or `field-entropy`.
[[nodiscard]] inline SlopePooling parse_slope_pooling(std::string_view name) {
  return detail::value_named(kSlopePoolings, name, "slope pooling");
}

/// One cell of a top-level region, re-mapped alone from a lower altitude on a training field
/// (calibration knows the truth): a row of the cell gain model.
struct CellSample {
  std::size_t field = 0;    ///< which calibration field it comes from (index)
  std::size_t region = 0;   ///< its region (top-level waypoint index) on that field
  double top_gsd_cm = 0.0;  ///< the GSD of the top-level image that saw it [cm/px]
  double sub_gsd_cm = 0.0;  ///< the GSD it was re-mapped at [cm/px]
  CellInputs top;           ///< the cell as the top-level image saw it
  /// The same quantities from the finer image over the cell (NaN values where unknown): what a
  /// descent shows in flight about how much surer the finer look is.
  CellInputs fine;
  double field_share = 0.0;  ///< the cell's field pixels / the field's
  double field_sigma = 0.0;  ///< σ of the field's top-level map (share of L over its field pixels)
  /// Share of the cell's field pixels whose label the re-mapping changed with L involved
  /// (observable in flight: no truth needed).
  double relabelled = 0.0;
  /// Of those, the shares that entered L and that left it (Relabelling::added_share,
  /// removed_share; observable in flight).
  double added = 0.0;
  double removed = 0.0;
  /// Truth needed: of those, the shares whose new side of L the ground truth gives (right).
  Relabelling right{};
  /// No truth: of those, the shares that the region's look at twice sub_gsd_cm also made, and of
  /// these the right ones (NaN where twice sub_gsd_cm was not a candidate): whether a second,
  /// coarser look that confirms a change tells a right one (only added_share, removed_share set).
  Relabelling confirmed{.added_share = std::numeric_limits<double>::quiet_NaN(),
                        .removed_share = std::numeric_limits<double>::quiet_NaN()};
  Relabelling confirmed_right = confirmed;
  /// CalibrationOptions::frame_check: the same for the region's map from frames shifted half a
  /// footprint along the rows, the same ground at the same GSD in another image's context.
  Relabelling reframed = confirmed, reframed_right = confirmed;
  /// Field mIoU over L of the top-level map with only this cell re-mapped, minus without.
  double field_gain = 0.0;
  /// The same comparison in pixels, summed over the classes of L (as RealisedDescent's): how
  /// many more true positives and false positives the field's map holds with the cell re-mapped
  /// (false negatives change by −delta_tp). A field's IoU of a class moves by about
  /// (ΔTP − IoU·ΔFP) / (TP + FP + FN): what a false positive costs depends on the field's own
  /// IoU, which a gain measured on a training field carries with it.
  std::int64_t delta_tp = 0;
  std::int64_t delta_fp = 0;
  /// The field's top-level map over L, in pixels summed over its classes: true positives, false
  /// positives, false negatives (its IoU and union, the exchange rate above).
  std::int64_t field_tp = 0;
  std::int64_t field_fp = 0;
  std::int64_t field_fn = 0;

  /// The field gain per unit of the cell's field share and of the field's σ (≈ the share of
  /// the cell's pixels corrected; RegionSample::normalized_field_gain for a region).
  [[nodiscard]] double normalized_gain() const noexcept {
    return field_share > 0.0 ? field_gain * field_sigma / field_share : 0.0;
  }
};

/// Every training field's cell samples in one list, field after field (calibration keeps them
/// per field: CalibrationResult::cell_samples, the cell gain model's fit, the folds' pooling).
[[nodiscard]] inline std::vector<CellSample> cells_of_every_field(std::span<const std::vector<CellSample>> cells) {
  std::vector<CellSample> all;
  for (const auto& c : cells) all.insert(all.end(), c.begin(), c.end());
  return all;
}

namespace detail {
/// The cell samples of one pair of top-level and descent GSDs.
struct GsdGroup {
  double top = 0.0, sub = 0.0;
  std::vector<const CellSample*> cells;
};

/// `samples` grouped by their pair of GSDs (detail::same_gsd), in the order each pair first occurs:
/// what CellGainModel::fit, relabel_transfer() and relabel_region_sd() each fit per pair.
inline std::vector<GsdGroup> group_by_gsds(std::span<const CellSample> samples) {
  std::vector<GsdGroup> groups;
  for (const CellSample& s : samples) {
    auto g = std::find_if(groups.begin(), groups.end(), [&](const GsdGroup& q) {
      return same_gsd(q.top, s.top_gsd_cm) && same_gsd(q.sub, s.sub_gsd_cm);
    });
    if (g == groups.end()) g = groups.insert(groups.end(), GsdGroup{s.top_gsd_cm, s.sub_gsd_cm, {}});
    g->cells.push_back(&s);
  }
  return groups;
}
}  // namespace detail

/// The cell gain model: per pair of top-level and descent GSD, how much of a cell's input x (a
/// decision input of the top-level image, e.g. its expected error about L) a re-mapping turns
/// into gain, and into relabelled pixels.
///
/// For a cell c with input value x_c seen at GSD g_top and re-mapped at g:
/// - its normalised gain ν_c (CellSample::normalized_gain) = β·x_c + ε, Var ε = κ·x_c;
/// - its relabelled share χ_c = α·x_c + ε', Var ε' = κ_χ·x_c;
/// β, α per (g_top, g): weighted least squares through the origin (weights: the cells' field
/// pixels) over the calibration cells of that pair, pooled over the training fields as
/// SlopePooling says (over their cells, or each field's own slope pooled as random effects:
/// field_slope); κ, κ_χ: the weighted mean squared residual about them per unit of x, over
/// every cell. The variance grows with x because a cell's errors are what a re-mapping can
/// change: the ground-truth oracle's expected error is exactly the share of pixels its
/// top-level map has wrong, and a re-mapping at the orthomosaic's GSD corrects all of them
/// (β ≈ 1, κ ≈ 0). A network's cells scatter about β·x (its confidence is only partly honest),
/// and β is smaller: a finer image of a cell corrects part of what the network got wrong and
/// gets some of the rest wrong. Between the calibrated descent GSDs of a top-level GSD the four
/// numbers are linear in g; beyond them, constant; a top-level GSD that was not calibrated
/// reads the nearest one that was.
///
/// A descent re-mapping a set S of cells of a region of R field pixels forecasts (as shares of
/// the region: the same units as GainModel's relabelled share)
/// gain = β·Σ_S v_c·x_c, Var = κ·Σ_S v_c²·x_c, v_c = CellInputs::gain_px / R (the pixels ν_c was
/// normalised by: with GainExtent::images the cell's whole footprint, which may overhang the
/// region), and the relabelled share α·Σ_S w_c·x_c, w_c = px_c / R (its pixels in the region).
///
/// What a descent shows, without ground truth (the scene check, FrontAwarePolicy::observe): the
/// finer images' own value of the input over the same cells, x'_c. Where the finer look is surer
/// (x' < x) the re-mapping corrected something, where it is less sure it likely did harm:
/// ν_c ≈ γ·(x_c − x'_c) on the training cells (γ by least squares through the origin), so
/// y = γ·Σ_S v_c·(x_c − x'_c) estimates the descent's realised gain. As a measurement of the
/// forecast β·Σ_S v_c·x_c its spread is κ_p·Σ_S v_c²·x_c, κ_p the weighted mean squared
/// difference per unit of x over the training cells: it holds how far the proxy misses and how
/// far the training fields' own gains scatter, so that the scene check learns no faster than the
/// training fields show it can. And the proxy's slope is a property of the field, not only of
/// the network: fitted on each training field alone, γ_f may even change sign between fields
/// (MobileNetV2's water: negative on three of the tiles it was trained on, positive on the one it
/// never saw). τ_γ, the spread of the γ_f about γ, adds τ_γ²·d² to the measurement's variance,
/// d = Σ_S v_c·(x_c − x'_c): a scene check on a field whose slope is any of the training fields'
/// is trusted no further than they agree. With one training field τ_γ = |γ| (how far the slope
/// transfers to another field is unknown). γ = κ_p = τ_γ = 0 where no fine inputs were known
/// (labels-only backends).
class CellGainModel {
 public:
  /// The model for one pair of top-level and descent GSDs.
  struct Point {
    double top_gsd_cm = 0.0;
    double sub_gsd_cm = 0.0;
    double gain_slope = 0.0;      ///< β
    double gain_noise = 0.0;      ///< κ >= 0
    double relabel_slope = 0.0;   ///< α
    double relabel_noise = 0.0;   ///< κ_χ >= 0
    double proxy_slope = 0.0;     ///< γ: gain per unit of the input the finer look removes
    double proxy_noise = 0.0;     ///< κ_p >= 0
    double proxy_slope_sd = 0.0;  ///< τ_γ >= 0: the spread of γ between the training fields
    /// SlopePooling::field_entropy (0 otherwise): β changes by `entropy_slope` per unit of the
    /// field's mean top-level entropy u from β at u = `entropy_reference`, u clamped to the
    /// training fields' range [`entropy_low`, `entropy_high`].
    double entropy_slope = 0.0;
    double entropy_reference = 0.0;
    double entropy_low = 0.0;
    double entropy_high = 0.0;

    /// β on a field of mean top-level entropy `u` (NaN: unknown, β at the reference).
    [[nodiscard]] double gain_slope_at(double u) const noexcept {
      if (!std::isfinite(u) || entropy_slope == 0.0) return gain_slope;
      return gain_slope + entropy_slope * (std::clamp(u, entropy_low, entropy_high) - entropy_reference);
    }
  };

  /// A forecast for a set of cells, in shares of the region's field pixels.
  struct Forecast {
    double gain = 0.0;  ///< normalised gain (× region share / field σ = field gain)
    double gain_var = 0.0;
    double relabelled = 0.0;  ///< relabelled share of the region with L involved
    double relabelled_var = 0.0;
    double input = 0.0;      ///< Σ v_c·x_c: the cells' input, what the finer look is compared with
    double proxy_var = 0.0;  ///< κ_p·Σ v_c²·x_c: the spread of the scene check's measurement
  };

  /// @throws std::invalid_argument for no point, GSDs that are not finite and positive with the
  ///         descent's finer than the top's, pairs not in increasing (top, descent) order, or a
  ///         slope or noise that is not finite (noise < 0).
  CellGainModel(DecisionInput input, std::vector<Point> points, SlopePooling pooling = SlopePooling::cells)
      : input_(input), pooling_(pooling), points_(std::move(points)) {
    detail::require(!points_.empty(), "CellGainModel: at least one point is needed; count", points_.size());
    for (std::size_t k = 0; k < points_.size(); ++k) {
      const Point& p = points_[k];
      detail::require(std::isfinite(p.top_gsd_cm) && std::isfinite(p.sub_gsd_cm) && p.sub_gsd_cm > 0.0 &&
                          p.sub_gsd_cm < p.top_gsd_cm,
                      "CellGainModel: a point needs finite GSDs, the descent's finer than the top's; descent GSD",
                      p.sub_gsd_cm);
      detail::require(k == 0 || p.top_gsd_cm > points_[k - 1].top_gsd_cm ||
                          (p.top_gsd_cm == points_[k - 1].top_gsd_cm && p.sub_gsd_cm > points_[k - 1].sub_gsd_cm),
                      "CellGainModel: points must be in increasing (top, descent) GSD order; descent GSD",
                      p.sub_gsd_cm);
      detail::require(std::isfinite(p.gain_slope) && std::isfinite(p.relabel_slope) && std::isfinite(p.gain_noise) &&
                          std::isfinite(p.relabel_noise) && p.gain_noise >= 0.0 && p.relabel_noise >= 0.0 &&
                          std::isfinite(p.proxy_slope) && std::isfinite(p.proxy_noise) && p.proxy_noise >= 0.0 &&
                          std::isfinite(p.proxy_slope_sd) && p.proxy_slope_sd >= 0.0 &&
                          std::isfinite(p.entropy_slope) && std::isfinite(p.entropy_reference) &&
                          std::isfinite(p.entropy_low) && std::isfinite(p.entropy_high) &&
                          p.entropy_low <= p.entropy_high,
                      "CellGainModel: slopes must be finite, noises finite and >= 0 and the entropy range ordered; "
                      "at descent GSD",
                      p.sub_gsd_cm);
    }
  }

  /// Fits the model of input `input` to `samples` (cells of every pair of GSDs), its slopes
  /// pooled over the training fields as `pooling` says.
  /// @throws std::invalid_argument for no sample, or a sample that is not finite.
  [[nodiscard]] static CellGainModel fit(std::span<const CellSample> samples, DecisionInput input,
                                         SlopePooling pooling = SlopePooling::cells) {
    detail::require(!samples.empty(), "CellGainModel::fit: number of samples must be > 0", 0);
    for (const CellSample& s : samples)
      detail::require(std::isfinite(s.top_gsd_cm) && std::isfinite(s.sub_gsd_cm) && std::isfinite(s.field_gain) &&
                          std::isfinite(s.relabelled) && std::isfinite(s.top.field_px) &&
                          std::isfinite(s.field_share) && std::isfinite(s.field_sigma),
                      "CellGainModel::fit: samples must be finite; field gain", s.field_gain);
    std::vector<Point> points;
    for (const detail::GsdGroup& g : detail::group_by_gsds(samples)) points.push_back(fit_group(g, input, pooling));
    std::sort(points.begin(), points.end(), [](const Point& a, const Point& b) {
      return a.top_gsd_cm < b.top_gsd_cm || (a.top_gsd_cm == b.top_gsd_cm && a.sub_gsd_cm < b.sub_gsd_cm);
    });
    return CellGainModel(input, std::move(points), pooling);
  }

  /// The forecast of re-mapping `cells`, seen at `top_gsd_cm`, at `sub_gsd_cm`, in shares of a
  /// region of `region_px` field pixels (see the class comment).
  /// @throws std::invalid_argument for `region_px` <= 0.
  [[nodiscard]] Forecast forecast(double top_gsd_cm, double sub_gsd_cm, std::span<const CellInputs> cells,
                                  double region_px) const {
    detail::require(region_px > 0.0, "CellGainModel::forecast: region_px must be > 0", region_px);
    const Point p = at(top_gsd_cm, sub_gsd_cm);
    double sx = 0.0, sxx = 0.0, gx = 0.0, gxx = 0.0;
    for (const CellInputs& c : cells) {
      const double w = c.field_px / region_px, v = c.gain_px() / region_px;
      sx += w * x_of(c);
      sxx += w * w * x_of(c);
      gx += v * x_of(c);
      gxx += v * v * x_of(c);
    }
    return {p.gain_slope * gx,  p.gain_noise * gxx, std::max(0.0, p.relabel_slope * sx), p.relabel_noise * sxx, gx,
            p.proxy_noise * gxx};
  }

  /// The scene check's estimate of a descent's normalised gain (in shares of its region) from
  /// the input its cells held at the top (`top_input`, Forecast::input) and in the finer images
  /// (`fine_input`, the same sum): γ·(top − fine); 0 where the model has no proxy.
  [[nodiscard]] double proxy_gain(double top_gsd_cm, double sub_gsd_cm, double top_input, double fine_input) const {
    return at(top_gsd_cm, sub_gsd_cm).proxy_slope * (top_input - fine_input);
  }

  /// The normalised gain one cell is forecast (β·x).
  [[nodiscard]] double cell_gain(double top_gsd_cm, double sub_gsd_cm, const CellInputs& cell) const {
    return at(top_gsd_cm, sub_gsd_cm).gain_slope * x_of(cell);
  }

  /// The model for a pair of GSDs (see the class comment).
  [[nodiscard]] Point at(double top_gsd_cm, double sub_gsd_cm) const {
    // The calibrated top-level GSD nearest `top_gsd_cm`, and its points (β at the field's entropy).
    const double top = nearest_top(top_gsd_cm);
    std::vector<Point> row;
    for (const Point& p : points_)
      if (p.top_gsd_cm == top) {
        row.push_back(p);
        row.back().gain_slope = p.gain_slope_at(field_entropy_);
      }
    Point out{top_gsd_cm, sub_gsd_cm, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    out.gain_slope = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::gain_slope);
    out.gain_noise = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::gain_noise);
    out.relabel_slope = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::relabel_slope);
    out.relabel_noise = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::relabel_noise);
    out.proxy_slope = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::proxy_slope);
    out.proxy_noise = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::proxy_noise);
    out.proxy_slope_sd = detail::interpolate_flat(row, sub_gsd_cm, &Point::sub_gsd_cm, &Point::proxy_slope_sd);
    return out;
  }

  /// The top-level GSDs the model was calibrated for, ascending.
  [[nodiscard]] std::vector<double> top_gsds() const {
    std::vector<double> out;
    for (const Point& p : points_)
      if (out.empty() || out.back() != p.top_gsd_cm) out.push_back(p.top_gsd_cm);
    return out;
  }

  /// The flown field's mean top-level entropy (SlopePooling::field_entropy: what at() reads β
  /// at; NaN, the default: unknown, β at each point's reference).
  void set_field_entropy(double u) noexcept { field_entropy_ = u; }
  [[nodiscard]] double field_entropy() const noexcept { return field_entropy_; }
  /// Whether β depends on the field's entropy (some point has an entropy slope).
  [[nodiscard]] bool reads_field_entropy() const noexcept {
    return std::any_of(points_.begin(), points_.end(), [](const Point& p) { return p.entropy_slope != 0.0; });
  }
  /// The training fields' mean top-level entropy at the calibrated top level nearest
  /// `top_gsd_cm` (the mean of its points' references; 0 without an entropy slope).
  [[nodiscard]] double entropy_reference(double top_gsd_cm) const {
    const double top = nearest_top(top_gsd_cm);
    double sum = 0.0;
    std::size_t n = 0;
    for (const Point& p : points_)
      if (p.top_gsd_cm == top && p.entropy_slope != 0.0) sum += p.entropy_reference, ++n;
    return n > 0 ? sum / static_cast<double>(n) : 0.0;
  }

  [[nodiscard]] DecisionInput input() const noexcept { return input_; }
  /// How the slopes were pooled over the training fields (what fit was told; saved in the model file).
  [[nodiscard]] SlopePooling pooling() const noexcept { return pooling_; }
  [[nodiscard]] const std::vector<Point>& points() const noexcept { return points_; }

 private:
  /// fit()'s point of one pair of GSDs: the slopes β and α, pooled as `pooling` says, then the
  /// noises about them and the scene check's proxy (fit_noises).
  static Point fit_group(const detail::GsdGroup& g, DecisionInput input, SlopePooling pooling) {
    double px = 0.0;
    for (const CellSample* c : g.cells) px += c->top.field_px;
    const double mean_px = px > 0.0 ? px / static_cast<double>(g.cells.size()) : 1.0;
    // Per training field, the sums of its own fits of β and α (pooled by field_slope) and its
    // mean top-level entropy (field_entropy).
    detail::PerField gain_sums, relabel_sums;
    double wx = 0.0;
    for (const CellSample* c : g.cells) {
      const double x = value_of(c->top, input), w = c->top.field_px / mean_px;
      // `cells`: every cell in one field's sums, one fit.
      const std::size_t field = pooling != SlopePooling::cells ? c->field : 0;
      detail::FieldSlopeSums& gain = detail::sums_of(gain_sums, field);
      gain.add(w, x, c->normalized_gain());
      gain.add_covariate(c->top.field_px, c->top.value(DecisionInput::entropy));
      detail::sums_of(relabel_sums, field).add(w, x, c->relabelled);
      wx += w * x;
    }
    Point p{g.top, g.sub, detail::field_slope(gain_sums), 0.0, detail::field_slope(relabel_sums), 0.0, 0.0, 0.0};
    if (pooling == SlopePooling::field_entropy) {
      const detail::PooledSlope b = detail::field_slope_by_covariate(gain_sums);
      p.gain_slope = b.at_reference;
      p.entropy_slope = b.per_unit;
      p.entropy_reference = b.reference;
      p.entropy_low = b.low;
      p.entropy_high = b.high;
    }
    fit_noises(g, input, mean_px, wx, gain_sums, p);
    return p;
  }

  /// fit_group()'s noises κ about the slopes and, where every cell has its finer look's input,
  /// the scene check's proxy γ (ν on d = x − x'), its noise and its spread between the fields.
  static void fit_noises(const detail::GsdGroup& g, DecisionInput input, double mean_px, double wx,
                         detail::PerField& gain_sums, Point& p) {
    double eg = 0.0, er = 0.0, wdd = 0.0, wdg = 0.0;
    detail::PerField proxy_sums;  // per training field, the proxy's own fit of ν on d = x − x' (τ_γ)
    bool proxy = true;
    for (const CellSample* c : g.cells) {
      const double x = value_of(c->top, input), w = c->top.field_px / mean_px;
      // β on the cell's own field (its entropy's, with field_entropy).
      const double beta =
          p.entropy_slope != 0.0 ? p.gain_slope_at(detail::sums_of(gain_sums, c->field).covariate()) : p.gain_slope;
      eg += w * std::pow(c->normalized_gain() - beta * x, 2);
      er += w * std::pow(c->relabelled - p.relabel_slope * x, 2);
      const double xf = c->fine.value(input);
      proxy = proxy && std::isfinite(c->top.value(input)) && std::isfinite(xf);
      if (!proxy) continue;
      wdd += w * (x - xf) * (x - xf);
      wdg += w * (x - xf) * c->normalized_gain();
      detail::sums_of(proxy_sums, c->field).add(w, x - xf, c->normalized_gain());
    }
    p.gain_noise = wx > 0.0 ? eg / wx : 0.0;
    p.relabel_noise = wx > 0.0 ? er / wx : 0.0;
    if (proxy && wdd > 0.0 && wx > 0.0) {
      p.proxy_slope = wdg / wdd;
      double ep = 0.0;
      for (const CellSample* c : g.cells) {
        const double x = value_of(c->top, input), w = c->top.field_px / mean_px;
        ep += w * std::pow(p.proxy_slope * (x - c->fine.value(input)) - p.gain_slope * x, 2);
      }
      p.proxy_noise = ep / wx;
      p.proxy_slope_sd = detail::field_slope_spread(proxy_sums, p.proxy_slope);
    }
  }

  [[nodiscard]] double x_of(const CellInputs& c) const noexcept { return value_of(c, input_); }

  /// The calibrated top-level GSD nearest `top_gsd_cm`.
  [[nodiscard]] double nearest_top(double top_gsd_cm) const noexcept {
    double top = points_.front().top_gsd_cm;
    for (const Point& p : points_)
      if (std::abs(p.top_gsd_cm - top_gsd_cm) < std::abs(top - top_gsd_cm)) top = p.top_gsd_cm;
    return top;
  }

  static double value_of(const CellInputs& c, DecisionInput input) noexcept {
    const double v = c.value(input);
    return std::isfinite(v) ? v : 0.0;
  }

  DecisionInput input_;
  SlopePooling pooling_ = SlopePooling::cells;
  std::vector<Point> points_;
  double field_entropy_ = std::numeric_limits<double>::quiet_NaN();  ///< set_field_entropy()
};

}  // namespace adaptseg
