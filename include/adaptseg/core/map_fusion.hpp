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
enum class MapFusion { finest, pooled, pooled_interest };

/// Every fusion and its name (in model files and on the command line).
inline constexpr std::array<detail::NamedValue<MapFusion>, 3> kMapFusions{{
    {MapFusion::finest, "finest"},
    {MapFusion::pooled, "pooled"},
    {MapFusion::pooled_interest, "pooled-interest"},
}};

/// Whether `f` pools the images' class probabilities (`pooled`, `pooled_interest`): the backend
/// must give them.
[[nodiscard]] constexpr bool pools_probabilities(MapFusion f) noexcept { return f != MapFusion::finest; }

/// "finest", "pooled" or "pooled-interest".
[[nodiscard]] inline const char* to_string(MapFusion f) { return detail::name_of(kMapFusions, f, "map fusion"); }

/// Parses a fusion's name.
/// @throws std::invalid_argument for anything else.
[[nodiscard]] inline MapFusion parse_map_fusion(const std::string& s) {
  return detail::value_named(kMapFusions, s, "map fusion");
}

}  // namespace adaptseg
