#pragma once
/// @file
/// Where a descent's gain is counted (GainExtent, an AdaptiveOptions setting that a decision
/// model records; docs/method.md, "Where calibration counts a descent's gain").

#include <adaptseg/core/detail/named_rows.hpp>

#include <array>
#include <string>

namespace adaptseg {

/// Which pixels a calibration sample's field gain counts (RegionSample::field_gain,
/// CellSample::field_gain, delta_tp, delta_fp), and with ranked cells which pixels each cell's
/// gain is normalised by there and forecast for in flight (CellInputs::gain_px); the rest of a
/// sample (relabelled shares, the cells' inputs, region shares) is the region's either way.
enum class GainExtent {
  /// The region's pixels alone: a descent's images are fused into a map of its region, the
  /// parts of them beyond it dropped (the paper's region samples).
  region,
  /// Every pixel the descent's images cover, fused into the field's map with the neighbouring
  /// regions' top-level images: what a flight realises (RealisedDescent::field_gain), where a
  /// finer grid that overhangs its region (DescentGrid) re-maps part of its neighbours too. A
  /// ranked cell is then weighed by its whole footprint's field pixels (CellSample::field_share,
  /// CellInputs::footprint_px), known before the flight from the field's mask, and forecast from
  /// the inputs it shows inside the region.
  images,
};

/// Every gain extent and its name (the programs' `--gain-extent`).
inline constexpr std::array<detail::NamedValue<GainExtent>, 2> kGainExtents{{
    {GainExtent::region, "region"},
    {GainExtent::images, "images"},
}};

/// "region" or "images".
[[nodiscard]] inline const char* to_string(GainExtent e) { return detail::name_of(kGainExtents, e, "gain extent"); }

/// Parses a gain extent's name.
/// @throws std::invalid_argument naming both for anything else.
[[nodiscard]] inline GainExtent parse_gain_extent(const std::string& s) {
  return detail::value_named(kGainExtents, s, "gain extent");
}

}  // namespace adaptseg
