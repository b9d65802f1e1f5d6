#pragma once
/// @file
/// How the field map combines several observations of one pixel (MissionOptions::map_fusion,
/// SemanticMap).

#include <adaptseg/core/detail/named_rows.hpp>

#include <array>
#include <string>

namespace adaptseg {

/// How SemanticMap combines the images that cover one orthomosaic pixel.
/// - `finest`: the label of the finest-GSD image wins, among equally fine ones the latest ("we
///   preserve the results obtained with the highest resolution", paper §3.1).
/// - `pooled` (beyond the paper): the class probabilities of every image are pooled
///   log-linearly, each image weighted by its resolution (1 / GSD), and the pixel takes the
///   class of the largest pooled log-probability. A descent's closer look still outweighs the
///   top-level one (three times at 5 against 15 cm/px), but where the closer look is unsure
///   and the top-level one was sure, the top-level one keeps the pixel: a network that on new
///   ground sees the class where there is none in a closer image no longer writes it over a
///   confident top-level map (docs/method.md, "Decisions where the paper is silent, and
///   departures"). Needs the backend's class probabilities (SegmentsWithProbabilities).
/// - `pooled_interest` (beyond the paper): as `pooled`, but a pixel that any image labelled with
///   a label of interest keeps one: where the pooled class is not of interest, the label of
///   interest of the largest pooled sum among those the pixel's images gave it. A closer look
///   then adds the class of interest where it sees it and the top level did not, and removes it
///   only where no image saw it: on ground the networks never trained on, a closer look's
///   additions of vegetation were right more often than they must be to raise its IoU on five
///   tiles of six, while the pooled map let a sure top-level look veto them
///   (docs/journal/2026-12-loto.md, thirty-eighth session). Not the default: flown on the 24
///   leave-one-tile-out runs it did worse than `pooled` (docs/results.md). Needs the labels of
///   interest.
/// - `pooled_guarded` (beyond the paper): as `pooled`, but where the images at the coarsest GSD
///   that saw a pixel (the top level's, on a descended pixel) give their most likely class a
///   pooled probability above SemanticMap::kGuardConfidence (0.75), the pixel keeps that class:
///   a closer look changes only what the top level was unsure of. On ground a network never
///   trained on, a closer look and a sure top level that disagree are mostly the closer look
///   wrong (tile 5's sea called vegetation from 5 cm/px at a median confidence of 0.89, where the
///   top level said water at 0.85), while the right changes fall where the top level hesitated
///   (tile 6's vegetation called water from 15 cm/px at a median of 0.63;
///   docs/journal/2026-12-guard.md). The threshold is what four of six leave-one-tile-out folds
///   choose on their five training tiles (the other two: 0.7, within 0.0001 of 0.75's mean).
///   Needs the class probabilities, and probabilities that hesitate where the network may be
///   wrong: with one-hot ones (the oracle's) every pixel's coarsest look is sure, and no closer
///   look changes the map.
enum class MapFusion { finest, pooled, pooled_interest, pooled_guarded };

/// Every fusion and its name (in model files and on the command line).
inline constexpr std::array<detail::NamedValue<MapFusion>, 4> kMapFusions{{
    {MapFusion::finest, "finest"},
    {MapFusion::pooled, "pooled"},
    {MapFusion::pooled_interest, "pooled-interest"},
    {MapFusion::pooled_guarded, "pooled-guarded"},
}};

/// Whether `f` pools the images' class probabilities (every fusion but `finest`): the backend
/// must give them.
[[nodiscard]] constexpr bool pools_probabilities(MapFusion f) noexcept { return f != MapFusion::finest; }

/// "finest", "pooled", "pooled-interest" or "pooled-guarded".
[[nodiscard]] inline const char* to_string(MapFusion f) { return detail::name_of(kMapFusions, f, "map fusion"); }

/// Parses a fusion's name.
/// @throws std::invalid_argument for anything else.
[[nodiscard]] inline MapFusion parse_map_fusion(const std::string& s) {
  return detail::value_named(kMapFusions, s, "map fusion");
}

}  // namespace adaptseg
