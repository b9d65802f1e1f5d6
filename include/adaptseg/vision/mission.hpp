#pragma once
/// @file
/// Mission execution shared by every strategy: fly to a waypoint, take the image, segment,
/// fuse, score, and account for time (docs/method.md, "Decisions where the paper is silent, and
/// departures"); and the fixed-altitude lawnmower.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/core/time_account.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/vision/detail/planner_clock.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/semantic_map.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg {

/// What happened at one waypoint.
struct WaypointRecord {
  Waypoint waypoint;
  int level = 0;                              ///< 0: top-level plan; 1: a sub-lawnmower waypoint
  double semantic_ratio = 0.0;                ///< σ of the segmentation over L (paper Eq. `eq:vr`)
  std::optional<double> image_miou_interest;  ///< per-image mIoU over L, if defined
  std::optional<double> image_miou_all;       ///< per-image mIoU over all classes, if defined
  /// Share of the footprint's valid ground-truth pixels in L (σ of the truth, not of the
  /// segmentation); set when the image carries ground truth.
  std::optional<double> truth_ratio;
  double segmentation_s = 0.0;  ///< segmentation time charged [s]
};

/// A finished mission: path, fused map, scores and time (paper §5.3 metrics).
struct MissionResult {
  std::string field;
  std::string strategy;
  std::string segmenter;
  std::vector<int> interest;
  std::vector<WaypointRecord> waypoints;  ///< in visiting order
  cv::Mat fused_labels;                   ///< SemanticMap::labels() at the end
  cv::Mat fused_gsd_cm;                   ///< SemanticMap::gsd_cm() at the end (+inf: unobserved)
  ConfusionMatrix confusion{1};           ///< fused map vs the field's ground truth
  TimeAccount time;                       ///< the mission's time: flight, segmentation, planning

  /// The mission's time, time.total_s() [s].
  [[nodiscard]] double total_s() const noexcept { return time.total_s(); }
  [[nodiscard]] std::optional<double> miou_interest() const { return confusion.miou(interest); }
  [[nodiscard]] std::optional<double> miou_all() const { return confusion.miou_all(); }
};

/// Executes waypoints one by one for a planner: the data flow sensor -> segmenter -> metrics,
/// and the time accounting (flight by the velocity-ramp model from the previous waypoint;
/// segmentation and planning measured, or fixed per image/waypoint). The map is the planner's
/// (run_lawnmower_mission's own, AdaptivePlanner's): the mission scores it at the end (finish()).
/// The mission starts at its first waypoint: take-off and landing are equal for every
/// strategy and are left out.
///
/// Holds a reference to `backend`, which must outlive the Mission.
template <SegmentationBackend Backend>
class Mission {
 public:
  /// @throws std::invalid_argument for invalid options, labels of interest out of the
  ///         field's range, or no labels of interest at all.
  Mission(const Field& field, Backend& backend, MissionOptions options, std::string strategy)
      : sensor_(field, CameraModel(options.camera)),
        timing_(options.timing),
        backend_(backend),
        options_(std::move(options)) {
    detail::check_fixed_times(options_);
    result_.field = field.name();
    result_.strategy = std::move(strategy);
    result_.segmenter = backend_.name();
    result_.interest = options_.interest.empty() ? field.interest() : options_.interest;
    detail::require(!result_.interest.empty(),
                    "Mission: no labels of interest (set 'interest' in field.yaml or pass them)", 0);
    for (int c : result_.interest)
      detail::require(c >= 0 && c < field.num_classes(), "Mission: label of interest out of range", c);
    result_.confusion = ConfusionMatrix(field.num_classes());
  }

  [[nodiscard]] const Field& field() const noexcept { return sensor_.field(); }
  [[nodiscard]] const CameraModel& camera() const noexcept { return sensor_.camera(); }
  [[nodiscard]] const TimingModel& timing() const noexcept { return timing_; }
  [[nodiscard]] const MissionOptions& options() const noexcept { return options_; }
  [[nodiscard]] const std::vector<int>& interest() const noexcept { return result_.interest; }
  [[nodiscard]] const std::vector<WaypointRecord>& records() const noexcept { return result_.waypoints; }
  /// Time spent so far [s] (flight + segmentation + planning).
  [[nodiscard]] double elapsed_s() const noexcept { return time_.total_s(); }
  /// The mission's time account: charged flight and segmentation by visit(), planning by
  /// charge_planning() or by a planner that shares it (run_adaptive_mission).
  [[nodiscard]] TimeAccount& time_account() noexcept { return time_; }
  /// Current position (the last waypoint visited), if any.
  [[nodiscard]] std::optional<Eigen::Vector3d> position() const {
    if (result_.waypoints.empty()) return std::nullopt;
    return result_.waypoints.back().waypoint.position;
  }

  /// The outcome of one visit: the image, its segmentation (checked once, here) and its record.
  struct Visit {
    Image image;
    /// The backend's labels and, if asked for and given (SegmentsWithProbabilities), its class
    /// probabilities and an ensemble's member votes.
    CheckedSegmentation segmentation;
    const WaypointRecord* record;
  };

  /// Flies to `w`, takes the image, segments it (segment_and_check(); with `probabilities`,
  /// the backend's class probabilities where it gives them, their computation counted in the
  /// segmentation time) and records it. Fusing it into a map is the caller's.
  Visit visit(const Waypoint& w, int level, bool probabilities = false) {
    if (const auto p = position()) time_.flight_s += timing_.segment_time_s(*p, w.position);
    Image image = sensor_.capture(w);
    const auto t0 = std::chrono::steady_clock::now();
    CheckedSegmentation s = segment_and_check(backend_, image, sensor_.field().num_classes(), probabilities);
    const double measured = detail::seconds_since(t0);
    const cv::Mat& labels = s.labels();

    WaypointRecord rec;
    rec.waypoint = w;
    rec.level = level;
    rec.semantic_ratio = semantic_ratio(labels, result_.interest, image.ignore_label);
    if (!image.ground_truth.empty()) {
      const ConfusionMatrix cm = image_confusion(image, labels, field().num_classes());
      rec.image_miou_interest = cm.miou(result_.interest);
      rec.image_miou_all = cm.miou_all();
      rec.truth_ratio = cm.truth_share(result_.interest);
    }
    rec.segmentation_s = options_.fixed_segmentation_time_s.value_or(measured);
    time_.segmentation_s += rec.segmentation_s;
    result_.waypoints.push_back(std::move(rec));
    return Visit{std::move(image), std::move(s), &result_.waypoints.back()};
  }

  /// Charges planning time: `measured_s`, or the fixed per-waypoint time if one is set.
  void charge_planning(double measured_s) { time_.planning_s += options_.fixed_planning_time_s.value_or(measured_s); }

  /// Scores `map` (of the field's size: the planner's map) as the mission's fused map and
  /// returns the result. Call once, at the end.
  /// @throws std::invalid_argument if `map` differs in size from the field.
  MissionResult finish(const SemanticMap& map) && {
    detail::require(map.labels().size() == field().labels().size(),
                    "Mission::finish: the map must have the field's size", map.labels().cols);
    result_.fused_labels = map.labels().clone();  // the map may go on changing
    result_.fused_gsd_cm = map.gsd_cm().clone();
    result_.confusion.add(field().labels(), map.labels(), field().ignore_label());
    result_.time = time_;
    return std::move(result_);
  }

 private:
  SimulatedSensor sensor_;
  TimingModel timing_;
  Backend& backend_;
  MissionOptions options_;
  MissionResult result_;
  TimeAccount time_;
};

/// The fixed-altitude lawnmower baseline (paper §5.2): the whole field at one GSD,
/// regions without a valid pixel skipped. Planning time: the plan's computation, spread
/// over its waypoints (or the fixed per-waypoint time). `overlap` (beyond the paper; default
/// none, as the paper): the images' along- and across-track overlap, see LawnmowerOverlap.
/// @throws std::invalid_argument if `gsd_cm` is finer than the field's GSD, for an overlap
///         outside [0, 0.9], and for the reasons of Mission's constructor.
template <SegmentationBackend Backend>
[[nodiscard]] MissionResult run_lawnmower_mission(const Field& field, double gsd_cm, Backend& backend,
                                                  const MissionOptions& options, LawnmowerOverlap overlap = {}) {
  detail::require(std::isfinite(gsd_cm) && gsd_cm >= field.gsd_cm() * (1.0 - 1e-9),
                  "run_lawnmower_mission: gsd_cm must be finite and not finer than the field's " +
                      std::to_string(field.gsd_cm()) + " cm/px",
                  gsd_cm);
  Mission<Backend> mission(field, backend, options, "lawnmower");
  const auto t0 = std::chrono::steady_clock::now();
  const LawnmowerPlanner planner(mission.camera(), overlap);
  const auto plan = planner.plan(field.area(), gsd_cm, {0.0, 0.0}, [&](const Area& a) { return field.has_valid(a); });
  const double per_waypoint = plan.empty() ? 0.0 : detail::seconds_since(t0) / static_cast<double>(plan.size());
  SemanticMap map(field.labels().size(), field.ignore_label(), options.map_fusion, mission.interest());
  const bool pooled = pools_probabilities(options.map_fusion);
  for (const auto& w : plan) {
    mission.charge_planning(per_waypoint);
    const auto v = mission.visit(w, 0, pooled);
    detail::require(!pooled || !v.segmentation.get().probabilities.empty(),
                    std::string("Mission: map fusion '") + to_string(options.map_fusion) +
                        "' needs a backend that gives class probabilities",
                    backend.name());
    map.fuse(v.image, v.segmentation.get());
  }
  return std::move(mission).finish(map);
}

}  // namespace adaptseg
