#pragma once
/// @file
/// The adaptive planner (paper §3.2, Fig. workflow): fly the top-level lawnmower at h_max,
/// segment each image, ask a DecisionPolicy whether to re-map the region from a lower
/// altitude, insert that sub-lawnmower before the next top-level waypoint, fuse, and feed the
/// outcome back to the policy. Optionally never exceeds a mission-time budget.
///
/// `AdaptivePlanner` is the planner itself, run step by step by whoever flies the UAV: ask
/// `next()` for a waypoint, fly there, take the image, `report()` it, repeat (live use: no
/// simulator, no ground truth). `run_adaptive_mission` (adaptive_mission.hpp) drives it in
/// simulation. Its settings and what it hands out (AdaptiveOptions, SurveyArea,
/// PlannedWaypoint, PlannerStep, DecisionRecord) are in adaptive_options.hpp.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/inspection_tour.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image_summary.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/semantic_map.hpp>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// The adaptive planner run step by step (paper §3.2, Fig. workflow), for a caller that flies
/// the UAV and takes the images: a companion computer, or the simulation driver
/// run_adaptive_mission.
///
/// Protocol: `next()` gives the waypoint to fly to (nullopt when the mission is complete);
/// the caller flies there, takes the image and calls `report()` with it, once. The planner
/// segments it with the backend (or takes the caller's labels), fuses it into its map, and at
/// a top-level waypoint i (GSD `top_gsd_cm`) decides: for each candidate GSD finer than the
/// top and not finer than the map, it plans the sub-lawnmower over the region (starting in the
/// corner nearest the UAV, cells without field skipped; with DescentCoverage::interest only the
/// cells that show a label of interest, see descent_plan()) and computes its exact extra time: the
/// flight i → sub-lawnmower → i+1 minus the flight i → i+1, plus the per-image segmentation
/// and per-waypoint planning estimates. Candidates that would break the budget are dropped; the
/// policy decides; a descent's waypoints come next (DescentSchedule::tour / row: next, or after
/// the last top-level image of the survey / of the row, as one tour with the other deferred
/// descents, as each was costed).
/// After a descent's last image, the region's σ at h' and what it relabelled (from the fused
/// map) go back to the policy (paper §3.2.3).
///
/// Time: the budget check uses the elapsed mission time the caller reports with each image,
/// or, if it reports none, the planner's own account (flight by the timing model along the
/// planned waypoints; segmentation and planning measured, or fixed per image / waypoint).
///
/// Holds references to `backend` and `policy`, which must outlive the planner.
///
/// @code
/// adaptseg::AdaptivePlanner planner(area, backend, policy, options);
/// while (const auto w = planner.next()) {
///   const cv::Mat bgr = fly_and_shoot(w->waypoint.position);         // the UAV's part
///   const auto step = planner.report(planner.image_at(measured_pose(), bgr));
///   if (step.decision && step.decision->decision.descend) { /* a sub-lawnmower comes (next) */ }
/// }
/// const adaptseg::SemanticMap& map = planner.map();
/// @endcode
template <SegmentationBackend Backend, DecisionPolicy Policy>
class AdaptivePlanner {
 public:
  /// Plans the top-level lawnmower over `area` (cells without field skipped).
  /// @throws std::invalid_argument for an invalid area (num_classes not set included), camera
  ///         or timing, no labels of interest (or one that is not a class index), a top GSD
  ///         finer than the map's, candidates that are not finer than the top (or none to
  ///         descend to), a budget that is not positive, or one too small for the top-level
  ///         coverage alone.
  AdaptivePlanner(SurveyArea area, Backend& backend, Policy& policy, AdaptiveOptions options)
      : camera_(options.mission.camera),
        timing_(options.mission.timing),
        area_(std::move(area)),
        map_(grid_size(area_), area_.ignore_label, options.mission.map_fusion),
        backend_(backend),
        policy_(policy),
        options_(std::move(options)),
        schedule_(descent_schedule_info(options_.schedule)),
        coverage_(descent_coverage_info(options_.coverage)) {
    const auto t0 = std::chrono::steady_clock::now();
    policy_.begin_mission();
    if (area_.valid_mask.empty()) {
      area_.valid_mask = cv::Mat(map_.labels().size(), CV_8UC1, cv::Scalar(0));
      area_.valid_mask(pixel_rect(area_.area) & grid()).setTo(255);
    }
    detail::check_fixed_times(options_.mission);
    const auto& interest = options_.mission.interest;
    detail::require(!interest.empty(), "AdaptivePlanner: no labels of interest (options.mission.interest)", 0);
    for (int c : interest)
      detail::require(
          c >= 0 && c < area_.num_classes,
          "AdaptivePlanner: a label of interest is not a class index 0.." + std::to_string(area_.num_classes - 1), c);
    const double map_gsd = area_.map_gsd_cm;
    detail::require(
        std::isfinite(options_.top_gsd_cm) && options_.top_gsd_cm >= map_gsd * (1.0 - 1e-9),
        "AdaptivePlanner: top_gsd_cm must not be finer than the map's " + std::to_string(map_gsd) + " cm/px",
        options_.top_gsd_cm);
    for (double g : options_.candidate_gsd_cm) {
      detail::require(std::isfinite(g) && g > 0.0 && g < options_.top_gsd_cm,
                      "AdaptivePlanner: candidate GSDs must be positive and finer than top_gsd_cm", g);
      if (g >= map_gsd * (1.0 - 1e-9)) candidates_.push_back(g);  // finer than the map: skip
    }
    // Without a candidate the planner could never descend: say so instead of flying a lawnmower.
    detail::require(!candidates_.empty(),
                    "AdaptivePlanner: no candidate GSD to descend to (options.candidate_gsd_cm is empty or every "
                    "one is finer than the map's " +
                        std::to_string(map_gsd) +
                        " cm/px); DecisionModel::adaptive_options sets the candidates a model was calibrated for",
                    options_.candidate_gsd_cm.size());
    if (options_.budget_s)
      detail::require(std::isfinite(*options_.budget_s) && *options_.budget_s > 0.0,
                      "AdaptivePlanner: budget_s must be finite and > 0", *options_.budget_s);

    // The area's lawnmowers at the candidate and top GSDs (what the mission could fly instead;
    // planned as run_lawnmower_mission plans them), for front-aware policies.
    for (double g : candidates_) lawnmowers_.push_back({g, 0.0, 0});
    lawnmowers_.push_back({options_.top_gsd_cm, 0.0, 0});
    for (LawnmowerCost& l : lawnmowers_) {
      const auto plan = top_level_plan(l.gsd_cm);
      l.flight_s = plan_flight_s(plan);
      l.images = plan.size();
    }
    // The top level: the options' top GSD, or another of the lawnmower GSDs where the policy
    // chooses one (ChoosesTopLevel); descents go to the candidates finer than it.
    top_gsd_cm_ = options_.top_gsd_cm;
    if constexpr (ChoosesTopLevel<Policy>) {
      const double g = policy_.top_gsd(lawnmower_forecasts(), options_.top_gsd_cm);
      const bool known =
          std::any_of(lawnmowers_.begin(), lawnmowers_.end(), [&](const LawnmowerCost& l) { return l.gsd_cm == g; });
      const bool below = std::any_of(candidates_.begin(), candidates_.end(), [&](double c) { return c < g; });
      if (!known || !below)
        throw std::logic_error("decision policy '" + std::string(policy_.name()) + "' chose the top-level GSD " +
                               std::to_string(g) +
                               " cm/px, which is not one of the lawnmower GSDs with a candidate "
                               "below it");
      top_gsd_cm_ = g;
      std::erase_if(candidates_, [&](double c) { return c >= g; });
    }
    top_ = top_level_plan(top_gsd_cm_);
    valid_px_ = cv::countNonZero(area_.valid_mask);
    charge_measured_planning(seconds_since(t0));
    window_last_ = schedule_.window_last(top_);
    // A schedule's windows must cut the lawnmower into runs of consecutive waypoints: each
    // waypoint's window ends at or after it, and where the previous window reaches it, it is that one.
    bool runs = window_last_.size() == top_.size();
    for (std::size_t i = 0; runs && i < top_.size(); ++i)
      runs = window_last_[i] >= i && window_last_[i] < top_.size() &&
             (i == 0 || window_last_[i - 1] < i || window_last_[i - 1] == window_last_[i]);
    if (!runs)
      throw std::logic_error(std::string("descent schedule '") + schedule_.name +
                             "': its windows are not runs of consecutive top-level waypoints");
    flight_after_.assign(top_.size() + 1, 0.0);
    for (std::size_t i = top_.size(); i-- > 1;)
      flight_after_[i - 1] = flight_after_[i] + timing_.segment_time_s(top_[i - 1].position, top_[i].position);
    if (options_.budget_s) {
      const double coverage =
          flight_after_[0] + static_cast<double>(top_.size()) * (segmentation_estimate() + planning_estimate());
      detail::require(coverage <= *options_.budget_s,
                      "AdaptivePlanner: budget_s [s] is too small for the top-level coverage, which needs " +
                          std::to_string(coverage) + " s",
                      *options_.budget_s);
    }
  }

  /// The next waypoint to fly to and take an image at; the same one again while its image has
  /// not been reported; nullopt once the mission is complete.
  [[nodiscard]] std::optional<PlannedWaypoint> next() {
    if (pending_) return path_.back();
    // A tour starts once the last top-level waypoint of its window (the survey, or the row) is
    // flown; once flown, it is cleared for the next window's.
    if (sub_next_ >= sub_.size() && tour_next_ < tour_order_.size() && top_next_ > 0 &&
        top_next_ - 1 == window_last_[top_next_ - 1])
      start_inspection();
    if (sub_next_ >= sub_.size() && top_next_ < top_.size() && tour_next_ > 0 && tour_next_ >= tour_order_.size())
      clear_tour();
    PlannedWaypoint p;
    if (sub_next_ < sub_.size()) {
      p.waypoint = sub_[sub_next_];
      p.level = 1;
      p.top_index = current_.top_index;
      p.decision = current_.decision;
      p.step = sub_next_++;
    } else if (top_next_ < top_.size()) {
      p.waypoint = top_[top_next_];
      p.top_index = top_next_++;
    } else {
      return std::nullopt;
    }
    p.index = path_.size();
    path_.push_back(p);
    pending_ = true;
    if (options_.mission.fixed_planning_time_s) planning_s_ += *options_.mission.fixed_planning_time_s;
    return p;
  }

  /// Reports the image taken at the pending waypoint; the planner segments it with the backend
  /// (the time it takes is the image's segmentation time) and goes on as the other overload.
  /// @throws std::invalid_argument as the other overload, and whatever the backend throws.
  PlannerStep report(const Image& image, std::optional<double> elapsed_s = std::nullopt) {
    check_report(image, elapsed_s);
    const auto t0 = std::chrono::steady_clock::now();
    // With the backend's class probabilities where it gives them and the decision or the map reads
    // them (a coverage that ranks cells: the cells' decision inputs at the top level,
    // image_summary.hpp, and in a descent's images the scene check's; MapFusion::pooled);
    // otherwise the labels alone.
    Segmentation s = wants_probabilities() ? segment_with_probabilities_checked(backend_, image, area_.num_classes)
                                           : Segmentation{segment_checked(backend_, image, area_.num_classes), {}};
    check_pooled(s, "the backend gives none");
    const auto segmented = std::chrono::steady_clock::now();
    const double segmentation_s = std::chrono::duration<double>(segmented - t0).count();  // as Mission measures it
    return accept(image, s, segmentation_s, elapsed_s, segmented);
  }

  /// Reports the image taken at the pending waypoint with its segmentation `labels`, which
  /// took `segmentation_s` [s] (ignored when the options fix a segmentation time). The image's
  /// pose (`position`, `footprint_px`, `yaw_deg`) is what gets fused: the waypoint's, or the
  /// one the UAV measured (see image_at()). `elapsed_s`: the mission time [s] the caller
  /// measured up to now (flight, segmentation, planning), used for the budget instead of the
  /// planner's own account. Nothing changes when it throws: the waypoint stays pending.
  /// @throws std::invalid_argument if no waypoint is pending (next() not called, or its image
  ///         already reported), for an image that is not of the camera's size or has no
  ///         footprint or a yaw that is not finite, labels that break the segmentation
  ///         contract (check_segmentation()), or a time that is negative or not finite.
  PlannerStep report(const Image& image, const cv::Mat& labels, double segmentation_s,
                     std::optional<double> elapsed_s = std::nullopt) {
    return report(image, Segmentation{labels, {}}, segmentation_s, elapsed_s);
  }

  /// As the labels overload, with the class probabilities behind the labels where the caller's
  /// segmentation gives them (Segmentation; the decision inputs that need them are unknown
  /// without).
  /// @throws std::invalid_argument as the labels overload, and for probabilities (member votes)
  ///         that break their contract (check_probabilities()).
  PlannerStep report(const Image& image, const Segmentation& segmentation, double segmentation_s,
                     std::optional<double> elapsed_s = std::nullopt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_report(image, elapsed_s);
    check_segmentation(segmentation.labels, image, area_.num_classes, "AdaptivePlanner::report: the labels reported");
    check_probabilities(segmentation.probabilities, segmentation.labels, image, area_.num_classes,
                        "AdaptivePlanner::report: the probabilities reported");
    check_probabilities(segmentation.member_votes, segmentation.labels, image, area_.num_classes,
                        "AdaptivePlanner::report: the member votes reported");
    detail::require(std::isfinite(segmentation_s) && segmentation_s >= 0.0,
                    "AdaptivePlanner::report: segmentation_s must be finite and >= 0", segmentation_s);
    check_pooled(segmentation, "none were reported");
    return accept(image, segmentation, segmentation_s, elapsed_s, t0);
  }

  /// The Image of a camera frame `bgr` (CV_8UC3, B, G, R of the camera's size, or empty) taken at
  /// `pose`: x, y [m] in the field frame, z the altitude above ground [m]. Nadir camera whose
  /// image x axis is turned `yaw_deg` counter-clockwise from the field's x axis (Image::yaw_deg;
  /// 0: the plan's heading); the GSD follows from the altitude, the footprint is centred under
  /// the camera, snapped to map pixels as SimulatedSensor does, and turned by the yaw when fused.
  /// @throws std::invalid_argument for a pose or yaw that is not finite or an altitude <= 0,
  ///         and a colour image of another size or type.
  [[nodiscard]] Image image_at(const Eigen::Vector3d& pose, cv::Mat bgr = {}, double yaw_deg = 0.0) const {
    detail::require(pose.allFinite(), "AdaptivePlanner::image_at: the pose must be finite", pose.transpose());
    detail::require(std::isfinite(yaw_deg), "AdaptivePlanner::image_at: yaw_deg must be finite", yaw_deg);
    detail::require(
        bgr.empty() || (bgr.type() == CV_8UC3 && bgr.cols == camera_.width_px() && bgr.rows == camera_.height_px()),
        "AdaptivePlanner::image_at: bgr must be CV_8UC3 of the camera's size " + std::to_string(camera_.width_px()) +
            "x" + std::to_string(camera_.height_px()),
        std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows));
    Image img;
    img.bgr = std::move(bgr);
    img.position = pose;
    img.gsd_cm = camera_.gsd_cm(pose.z());
    img.width_px = camera_.width_px();
    img.height_px = camera_.height_px();
    img.ignore_label = area_.ignore_label;
    const Extent fp = camera_.footprint_at_gsd(img.gsd_cm);
    img.footprint_px = pixel_rect({pose.x() - 0.5 * fp.width_m, pose.y() - 0.5 * fp.height_m,
                                   pose.x() + 0.5 * fp.width_m, pose.y() + 0.5 * fp.height_m});
    img.yaw_deg = yaw_deg;
    return img;
  }

  /// The sub-lawnmower that re-maps the region of top-level waypoint `top_index` at `gsd_cm`
  /// (paper §3.2.1 W^{h'}): its grid laid as AdaptiveOptions::grid_anchor says (from the region's
  /// corner nearest that waypoint, or centred on the region), visited from the corner nearest
  /// the waypoint, cells without field skipped.
  /// @throws std::invalid_argument for an index out of range or a GSD that is not positive.
  [[nodiscard]] std::vector<Waypoint> sub_plan(std::size_t top_index, double gsd_cm) const {
    detail::require(top_index < top_.size(), "AdaptivePlanner::sub_plan: top_index out of range", top_index);
    const Waypoint& t = top_[top_index];
    return LawnmowerPlanner(camera_).plan(sub_grid(t, gsd_cm), gsd_cm, Eigen::Vector2d(t.position.x(), t.position.y()),
                                          keep());
  }

  /// The sub-lawnmower a descent at top-level waypoint `top_index` flies at `gsd_cm` once the
  /// region's top-level image is fused: sub_plan() with the cells `options().coverage` flies
  /// (DescentCoverageInfo::flies, given the region's map; DescentCoverage::interest: only the
  /// cells whose ground, grown by one top-level pixel and clipped to the region, shows a label of
  /// interest; visiting order unchanged). A coverage that ranks cells offers subsets of it.
  /// @throws std::invalid_argument as sub_plan().
  [[nodiscard]] std::vector<Waypoint> descent_plan(std::size_t top_index, double gsd_cm) const {
    if (!coverage_.flies) return sub_plan(top_index, gsd_cm);
    detail::require(top_index < top_.size(), "AdaptivePlanner::descent_plan: top_index out of range", top_index);
    const Waypoint& t = top_[top_index];
    const cv::Rect region = region_rect(top_index);
    const cv::Mat labels = map_.labels()(region);
    const auto keep_cell = [&](const Area& a) {
      return valid_pixels(a) > 0 && coverage_.flies(labels, pixel_rect(a) - region.tl(), top_gsd_cm_, area_.map_gsd_cm,
                                                    options_.mission.interest);
    };
    return LawnmowerPlanner(camera_).plan(sub_grid(t, gsd_cm), gsd_cm, Eigen::Vector2d(t.position.x(), t.position.y()),
                                          keep_cell);
  }

  /// The map pixels of top-level waypoint `top_index`'s region: its footprint, clipped to the
  /// map grid.
  /// @throws std::out_of_range for an index out of range.
  [[nodiscard]] cv::Rect region_rect(std::size_t top_index) const {
    return pixel_rect(top_.at(top_index).footprint) & grid();
  }

  /// The waypoints of the descent in progress, in visiting order: decided at the last
  /// top-level image, or (DescentSchedule::tour / row) the inspection being flown; empty when
  /// none is in progress or decided.
  [[nodiscard]] const std::vector<Waypoint>& descent() const noexcept { return sub_; }

  /// The top-level lawnmower W^{h_max}.
  [[nodiscard]] const std::vector<Waypoint>& top_level() const noexcept { return top_; }
  /// The GSD it is flown at [cm/px]: the options' top GSD, or the policy's choice
  /// (ChoosesTopLevel).
  [[nodiscard]] double top_gsd_cm() const noexcept { return top_gsd_cm_; }
  /// The candidate GSDs a descent may fly [cm/px] (those not finer than the map, finer than
  /// the top level).
  [[nodiscard]] const std::vector<double>& candidate_gsd_cm() const noexcept { return candidates_; }
  /// Every waypoint next() may hand out: the top level and, per region, every candidate's
  /// sub-lawnmower (what a pre-recorded image set must cover).
  [[nodiscard]] std::vector<Waypoint> reachable_waypoints() const {
    std::vector<Waypoint> out = top_;
    for (std::size_t i = 0; i < top_.size(); ++i)
      for (double g : candidates_) {
        const auto sub = sub_plan(i, g);
        out.insert(out.end(), sub.begin(), sub.end());
      }
    return out;
  }

  /// True once every waypoint has been handed out and reported.
  [[nodiscard]] bool done() const noexcept {
    return !pending_ && sub_next_ >= sub_.size() && top_next_ >= top_.size() && tour_next_ >= tour_order_.size();
  }
  /// The waypoint whose image is awaited, if any.
  [[nodiscard]] std::optional<PlannedWaypoint> pending() const {
    return pending_ ? std::optional<PlannedWaypoint>(path_.back()) : std::nullopt;
  }
  /// The fused segmentations (paper §3.1: the finest GSD wins), over the map grid.
  [[nodiscard]] const SemanticMap& map() const noexcept { return map_; }
  /// One record per top-level image reported so far.
  [[nodiscard]] const std::vector<DecisionRecord>& decisions() const noexcept { return decisions_; }
  /// Every waypoint handed out so far, in visiting order (the last may be pending).
  [[nodiscard]] const std::vector<PlannedWaypoint>& path() const noexcept { return path_; }
  [[nodiscard]] const SurveyArea& area() const noexcept { return area_; }
  [[nodiscard]] const CameraModel& camera() const noexcept { return camera_; }
  [[nodiscard]] const TimingModel& timing() const noexcept { return timing_; }
  [[nodiscard]] const AdaptiveOptions& options() const noexcept { return options_; }

  /// Mission time so far [s]: what the caller reported with the last image if it did,
  /// otherwise the planner's own account (flight + segmentation + planning).
  [[nodiscard]] double elapsed_s() const noexcept {
    return reported_elapsed_s_.value_or(flight_s_ + segmentation_s_ + planning_s_);
  }

  /// Measured planner computation [s] since the last call (planning the top level, decisions,
  /// online updates): what a caller keeping its own time account charges as planning time.
  [[nodiscard]] double take_planning_s() noexcept { return std::exchange(untaken_planning_s_, 0.0); }

  /// The pixels of the map grid under `a` (raster_rect, as Field::pixel_rect); may extend
  /// beyond the grid.
  [[nodiscard]] cv::Rect pixel_rect(const Area& a) const {
    return raster_rect(a, area_.map_gsd_cm, map_.labels().rows);
  }

  /// Field pixels of the map grid under `a`.
  [[nodiscard]] int valid_pixels(const Area& a) const {
    const cv::Rect in = pixel_rect(a) & grid();
    return in.area() > 0 ? cv::countNonZero(area_.valid_mask(in)) : 0;
  }

  /// Share of the ground under `a` that is field (paper: DecisionContext::valid_fraction).
  [[nodiscard]] double valid_fraction(const Area& a) const {
    const cv::Rect rect = pixel_rect(a);
    if (rect.area() <= 0) return 0.0;
    return static_cast<double>(valid_pixels(a)) / static_cast<double>(rect.area());
  }

 private:
  /// A descent the policy chose.
  struct ChosenDescent {
    std::size_t decision = 0;   ///< index into decisions_
    std::size_t top_index = 0;  ///< its region's top-level waypoint
    double altitude_m = 0.0;    ///< h'
    std::size_t ordinal = 0;    ///< 0, 1, ... in the order chosen (DescentOutcome::descent)
    std::vector<Waypoint> plan;
    bool deferred = false;  ///< flown in a tour (DescentSchedule::tour, row), not at once
  };

  /// A reported image and its checked labels: the time account, the fused map, and at a
  /// top-level waypoint the decision, after a descent's last image its outcome. The planner's
  /// processing since `t0` is charged as planning time.
  PlannerStep accept(const Image& image, const Segmentation& segmentation, double segmentation_s,
                     std::optional<double> elapsed_s, std::chrono::steady_clock::time_point t0) {
    const cv::Mat& labels = segmentation.labels;
    pending_ = false;
    reported_elapsed_s_ = elapsed_s;
    const PlannedWaypoint& p = path_.back();
    const double leg =
        p.index > 0 ? timing_.segment_time_s(path_[p.index - 1].waypoint.position, p.waypoint.position) : 0.0;
    flight_s_ += leg;
    const double seg = options_.mission.fixed_segmentation_time_s.value_or(segmentation_s);
    segmentation_s_ += seg;
    slowest_segmentation_s_ = std::max(slowest_segmentation_s_, seg);
    // What this step cost beyond the flight model's leg (the mission clock's advance since the
    // last image: segmentation, the planner's own time, and whatever else the caller's clock
    // counted), for the budget's bound of the steps to come.
    const double now = this->elapsed_s();
    slowest_step_s_ = std::max(slowest_step_s_, std::max(0.0, now - elapsed_at_last_image_s_ - leg));
    elapsed_at_last_image_s_ = now;
    ++steps_;
    // A descent's first image: the region's map before the descent (what its outcome compares).
    if (p.level == 1 && p.step == 0) {
      descent_before_ = map_.labels()(region_rect(p.top_index)).clone();
      fine_mass_ = 0.0;
      fine_known_ = true;
    }
    // Ranked cells: the finer image's own value of the ranking input over its cell (the scene check).
    if (p.level == 1 && coverage_.ranks_cells) {
      const cv::Rect region = region_rect(p.top_index);
      const cv::Rect cell = pixel_rect(p.waypoint.footprint) & region;
      if (cell.area() > 0) {
        scene_inputs_.assign(image, segmentation, options_.mission.interest, area_.ignore_label, cell,
                             std::array{options_.cell_input}, GridInputs::Cells::one);
        const CellInputs c = scene_inputs_.cell(area_.valid_mask(cell), cv::Rect(0, 0, cell.width, cell.height));
        fine_known_ = fine_known_ && (c.field_px == 0.0 || std::isfinite(c.value(options_.cell_input)));
        fine_mass_ += c.mass(options_.cell_input);
      }
    }
    map_.fuse(image, segmentation);

    // A budget that can no longer afford the rest of the descent (the bound of a step, learned
    // since the descent was chosen, may have grown) ends it here.
    if (p.level == 1 && sub_next_ < sub_.size() && options_.budget_s && !descent_rest_fits()) {
      sub_.resize(sub_next_);
      cut_short_ = true;
    }
    PlannerStep step;
    step.waypoint = p;
    step.sigma = semantic_ratio(labels, options_.mission.interest, image.ignore_label);
    if (p.level == 0)
      step.decision = decide(p, step.sigma, image, segmentation);
    else if (sub_next_ == sub_.size())
      step.outcome = finish_descent();
    charge_measured_planning(seconds_since(t0));
    return step;
  }

  static double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  /// The map grid's size: the mask's, or just enough to cover the area.
  static cv::Size grid_size(const SurveyArea& a) {
    const Area& r = a.area;
    detail::require_positive(a.map_gsd_cm, "SurveyArea: map_gsd_cm");
    detail::require(
        std::isfinite(r.x_min_m) && std::isfinite(r.y_min_m) && r.x_min_m >= 0.0 && r.y_min_m >= 0.0 &&
            std::isfinite(r.width_m()) && r.width_m() > 0.0 && std::isfinite(r.height_m()) && r.height_m() > 0.0,
        "SurveyArea: area must be finite with x_min, y_min >= 0 and a positive size [m]", r.width_m() * r.height_m());
    detail::require(a.num_classes >= 1 && a.num_classes <= 255,
                    "SurveyArea: num_classes must be the size of the backend's class set, 1..255 "
                    "(SurveyArea::of(field) sets it)",
                    a.num_classes);
    detail::require(a.ignore_label >= a.num_classes && a.ignore_label <= 255,
                    "SurveyArea: ignore_label must be in num_classes..255, not a class index", a.ignore_label);
    const double s = 100.0 / a.map_gsd_cm;
    if (a.valid_mask.empty())
      return {static_cast<int>(std::ceil(r.x_max_m * s - 1e-6)), static_cast<int>(std::ceil(r.y_max_m * s - 1e-6))};
    detail::require(a.valid_mask.type() == CV_8UC1, "SurveyArea: valid_mask must be CV_8UC1", a.valid_mask.type());
    detail::require(r.x_max_m * s <= a.valid_mask.cols + 0.5 && r.y_max_m * s <= a.valid_mask.rows + 0.5,
                    "SurveyArea: area must lie inside the valid mask's grid",
                    std::to_string(a.valid_mask.cols) + "x" + std::to_string(a.valid_mask.rows) + " px");
    return a.valid_mask.size();
  }

  [[nodiscard]] cv::Rect grid() const { return {0, 0, map_.labels().cols, map_.labels().rows}; }

  /// Which lawnmower cells to fly: those with any field under them.
  [[nodiscard]] auto keep() const {
    return [this](const Area& a) { return valid_pixels(a) > 0; };
  }

  /// A lawnmower over the whole area at `gsd_cm`, its grid laid as AdaptiveOptions::grid_anchor
  /// says, the cells without valid ground left out.
  [[nodiscard]] std::vector<Waypoint> top_level_plan(double gsd_cm) const {
    const LawnmowerPlanner planner(camera_);
    const Area laid =
        options_.grid_anchor == GridAnchor::centred ? planner.centred_grid(area_.area, gsd_cm) : area_.area;
    return planner.plan(laid, gsd_cm, Eigen::Vector2d(laid.x_min_m, laid.y_min_m), keep());
  }

  /// The rectangle a descent's sub-lawnmower at `gsd_cm` is laid on over top-level waypoint
  /// `t`'s region: the region itself (GridAnchor::corner: the grid grows from the corner nearest
  /// the waypoint, the region's centre, so which side overhangs is a tie that the frame's axes
  /// and round-off break), or the grid centred on the part of the region inside the area
  /// (GridAnchor::centred: every waypoint inside the area, as the top level's, and the same
  /// waypoints on the ground in any frame of the same site).
  [[nodiscard]] Area sub_grid(const Waypoint& t, double gsd_cm) const {
    if (options_.grid_anchor != GridAnchor::centred) return t.footprint;
    const Area& a = area_.area;
    const Area inside{std::max(t.footprint.x_min_m, a.x_min_m), std::max(t.footprint.y_min_m, a.y_min_m),
                      std::min(t.footprint.x_max_m, a.x_max_m), std::min(t.footprint.y_max_m, a.y_max_m)};
    // A region that does not reach into the area (no cell of it is kept anyway): the region.
    const bool empty = !(inside.x_max_m > inside.x_min_m && inside.y_max_m > inside.y_min_m);
    return LawnmowerPlanner(camera_).centred_grid(empty ? t.footprint : inside, gsd_cm);
  }

  [[nodiscard]] double segmentation_estimate() const {
    return options_.mission.fixed_segmentation_time_s.value_or(1.25 * slowest_segmentation_s_);
  }
  [[nodiscard]] double planning_estimate() const { return options_.mission.fixed_planning_time_s.value_or(0.0); }

  /// What the budget reserves for each step still to come beyond its flight [s]: with fixed
  /// segmentation and planning times, their sum (exact); otherwise a bound learned from the
  /// steps so far, each step's advance of the mission clock beyond the flight model's leg: the
  /// largest of k steps times (k + 1) / k (for processing times spread uniformly up to some
  /// limit, an unbiased estimate of the limit; generous while few steps are seen), and never
  /// less than segmentation_estimate(). 0 before the first image.
  [[nodiscard]] double step_bound() const {
    if (times_fixed()) return segmentation_estimate() + planning_estimate();
    if (steps_ == 0) return segmentation_estimate();
    const double k = static_cast<double>(steps_);
    return std::max(segmentation_estimate(), slowest_step_s_ * (k + 1.0) / k);
  }
  [[nodiscard]] bool times_fixed() const {
    return options_.mission.fixed_segmentation_time_s.has_value() && options_.mission.fixed_planning_time_s.has_value();
  }

  void charge_measured_planning(double s) {
    untaken_planning_s_ += s;
    if (!options_.mission.fixed_planning_time_s) planning_s_ += s;
  }

  /// Whether the planner needs the class probabilities behind each image's labels: for the
  /// decision inputs of a coverage that ranks cells, and for a pooled map.
  [[nodiscard]] bool wants_probabilities() const noexcept {
    return coverage_.ranks_cells || map_.fusion() == MapFusion::pooled;
  }

  /// @throws std::invalid_argument for a pooled map and a segmentation without probabilities.
  void check_pooled(const Segmentation& s, const char* why) const {
    detail::require(map_.fusion() == MapFusion::finest || !s.probabilities.empty(),
                    "AdaptivePlanner::report: map fusion 'pooled' needs the class probabilities behind the labels",
                    why);
  }

  void check_report(const Image& image, std::optional<double> elapsed_s) const {
    detail::require(pending_,
                    "AdaptivePlanner::report: no waypoint is waiting for an image (call next() first; "
                    "each waypoint takes one image)",
                    path_.size());
    detail::require(image.width_px == camera_.width_px() && image.height_px == camera_.height_px(),
                    "AdaptivePlanner::report: the image must have the camera's size " +
                        std::to_string(camera_.width_px()) + "x" + std::to_string(camera_.height_px()),
                    std::to_string(image.width_px) + "x" + std::to_string(image.height_px));
    detail::require(image.bgr.empty() || image.bgr.size() == cv::Size(image.width_px, image.height_px),
                    "AdaptivePlanner::report: the image's rgb must be of its size",
                    std::to_string(image.bgr.cols) + "x" + std::to_string(image.bgr.rows));
    detail::require(image.footprint_px.width > 0 && image.footprint_px.height > 0 && image.gsd_cm > 0.0,
                    "AdaptivePlanner::report: the image has no footprint (make it with image_at())", image.gsd_cm);
    detail::require(std::isfinite(image.yaw_deg), "AdaptivePlanner::report: the image's yaw_deg must be finite",
                    image.yaw_deg);
    if (elapsed_s)
      detail::require(std::isfinite(*elapsed_s) && *elapsed_s >= 0.0,
                      "AdaptivePlanner::report: elapsed_s must be finite and >= 0", *elapsed_s);
  }

  /// The area's lawnmowers at the candidate and nominal top GSDs with their forecast times:
  /// flight plus the per-image segmentation and planning estimates.
  [[nodiscard]] std::vector<LawnmowerForecast> lawnmower_forecasts() const {
    const double per_image = segmentation_estimate() + planning_estimate();
    std::vector<LawnmowerForecast> out;
    for (const auto& l : lawnmowers_) out.push_back({l.gsd_cm, l.flight_s + static_cast<double>(l.images) * per_image});
    return out;
  }

  /// Flight time along `plan`'s waypoints, in order [s].
  [[nodiscard]] double plan_flight_s(const std::vector<Waypoint>& plan) const {
    double t = 0.0;
    for (std::size_t k = 1; k < plan.size(); ++k) t += timing_.segment_time_s(plan[k - 1].position, plan[k].position);
    return t;
  }

  /// What a descent at top-level waypoint i may fly at one GSD: its sub-lawnmower and, for a
  /// coverage that ranks cells, the cells it re-maps.
  struct DescentOption {
    double gsd_cm = 0.0;
    std::vector<Waypoint> plan;
    std::vector<CellInputs> cells;
  };

  /// The decision input the cells are ranked by (`options().cell_input`) of the top-level image
  /// of waypoint i (`image`, `segmentation`) over its region on the map grid (GridInputs, its
  /// buffers kept from image to image); none unless the coverage ranks cells.
  [[nodiscard]] const GridInputs* region_inputs(std::size_t i, const Image& image, const Segmentation& segmentation) {
    const cv::Rect region = region_rect(i);
    if (!coverage_.ranks_cells || region.area() == 0) return nullptr;
    if (reads_field_entropy())
      region_inputs_.assign(image, segmentation, options_.mission.interest, area_.ignore_label, region,
                            std::array{options_.cell_input, DecisionInput::entropy});
    else
      region_inputs_.assign(image, segmentation, options_.mission.interest, area_.ignore_label, region,
                            std::array{options_.cell_input});
    return &region_inputs_;
  }

  /// Whether the policy reads the field's mean top-level entropy (ReadsFieldEntropy).
  [[nodiscard]] bool reads_field_entropy() const {
    if constexpr (ReadsFieldEntropy<Policy>)
      return policy_.reads_field_entropy();
    else
      return false;
  }

  /// Every descent the decision at top-level waypoint i may choose from, per candidate GSD:
  /// descent_plan(), or for a coverage that ranks cells (DescentCoverage::ranked) its cells
  /// ranked by their mass of `options().cell_input` in the region's inputs (`inputs`,
  /// region_inputs()), one option per number k of the best cells (cells without any of the
  /// input left out), each flown in the sub-lawnmower's order.
  [[nodiscard]] std::vector<DescentOption> descent_options(std::size_t i, const GridInputs* inputs) const {
    std::vector<DescentOption> out;
    if (!coverage_.ranks_cells) {
      for (double g : candidates_) out.push_back({g, descent_plan(i, g), {}});
      return out;
    }
    const cv::Rect region = region_rect(i);
    if (region.area() == 0 || !inputs) return out;
    const cv::Mat field = area_.valid_mask(region);
    const DecisionInput input = options_.cell_input;
    for (double g : candidates_) {
      const std::vector<Waypoint> all = descent_plan(i, g);
      std::vector<CellInputs> cells;
      std::vector<std::size_t> ranked;
      for (std::size_t k = 0; k < all.size(); ++k) {
        cells.push_back(inputs->cell(field, (pixel_rect(all[k].footprint) & region) - region.tl()));
        if (cells.back().mass(input) > 0.0) ranked.push_back(k);
      }
      std::stable_sort(ranked.begin(), ranked.end(),
                       [&](std::size_t a, std::size_t b) { return cells[a].mass(input) > cells[b].mass(input); });
      std::vector<bool> chosen(all.size(), false);
      for (std::size_t n = 0; n < ranked.size(); ++n) {
        chosen[ranked[n]] = true;
        DescentOption o{g, {}, {}};
        for (std::size_t k = 0; k < all.size(); ++k)
          if (chosen[k]) o.plan.push_back(all[k]), o.cells.push_back(cells[k]);
        out.push_back(std::move(o));
      }
    }
    return out;
  }

  /// The decision at top-level waypoint `p` (paper §3.2.2), its candidates with exact costs.
  DecisionRecord decide(const PlannedWaypoint& p, double sigma, const Image& image, const Segmentation& segmentation) {
    const std::size_t i = p.top_index;
    DecisionRecord rec;
    rec.waypoint_index = p.index;
    rec.sigma = sigma;
    const Eigen::Vector3d here = top_[i].position;
    const bool last = i + 1 == top_.size();
    const bool tour = schedule_.defers;
    const bool window_last = i == window_last_[i];  // the tour (of the survey / row) starts here
    const double per_image = segmentation_estimate() + planning_estimate();
    const double direct = last ? 0.0 : timing_.segment_time_s(here, top_[i + 1].position);
    // Time still needed after this waypoint's decision to finish the top-level coverage (and
    // the tour chosen so far: what it adds to the top-level legs).
    double rest_flight = last ? 0.0 : direct + flight_after_[i + 1];
    double rest_images = static_cast<double>(top_.size() - i - 1);
    if (tour) rest_flight += tour_extra_s(i), rest_images += static_cast<double>(tour_images_);
    const double rest = rest_flight + rest_images * per_image;
    // The budget reserves a bound of each step's processing instead of the estimate, and, where
    // times are measured, one for what is left of this step (this decision, not yet charged).
    const double bound = step_bound();
    const double reserved = rest_flight + rest_images * bound + (times_fixed() ? 0.0 : bound);
    const double elapsed = elapsed_s();
    std::vector<std::vector<Waypoint>> sub_plans;
    std::vector<std::pair<TourStop, TourInsertion>> stops;  // per candidate, for a deferred descent
    const GridInputs* inputs = region_inputs(i, image, segmentation);
    for (DescentOption& option : descent_options(i, inputs)) {
      const double g = option.gsd_cm;
      std::vector<Waypoint>& sub = option.plan;
      if (sub.empty()) continue;
      const double inner = plan_flight_s(sub);
      // What descending adds to the flight: at once, down and back up to the next waypoint ...
      double flight = timing_.segment_time_s(here, sub.front().position) + inner - direct;
      if (!last) flight += timing_.segment_time_s(sub.back().position, top_[i + 1].position);
      // ... or, on a tour, inserted where it adds least (if that is less). At the window's
      // last top-level waypoint, where a tour already chosen starts, flying it at once is the
      // insertion at the tour's head, so the tour prices it (the at-once cost above would
      // ignore that the tour then starts from the descent's end).
      const TourStop stop{sub.front().position, sub.back().position, inner};
      TourInsertion insertion;
      bool deferred = false;
      if (tour) {
        insertion = cheapest_insertion(timing_, tour_start(i), tour_stops_, tour_order_, stop, tour_end(i));
        deferred = (window_last && !tour_order_.empty()) || insertion.added_s < flight;
        if (deferred) flight = insertion.added_s;
      }
      Candidate c;
      c.deferred = deferred;
      c.gsd_cm = g;
      c.altitude_m = camera_.altitude_m(g);
      c.images = static_cast<int>(sub.size());
      c.extra_time_s = flight + static_cast<double>(sub.size()) * per_image;
      c.cells = std::move(option.cells);
      // Descending replaces the direct leg to i+1: elapsed + extra + rest must fit, each image
      // reserved at the bound.
      if (options_.budget_s &&
          elapsed + flight + static_cast<double>(sub.size()) * bound + reserved > *options_.budget_s + 1e-9) {
        rec.budget_limited = true;
        continue;
      }
      rec.candidates.push_back(c);
      sub_plans.push_back(std::move(sub));
      stops.emplace_back(stop, insertion);
    }
    const std::vector<LawnmowerForecast> forecasts = lawnmower_forecasts();
    DecisionContext ctx;
    ctx.sigma = rec.sigma;
    ctx.valid_fraction = valid_fraction(top_[i].footprint);
    ctx.top_gsd_cm = top_gsd_cm_;
    ctx.top_altitude_m = here.z();
    ctx.candidates = rec.candidates;
    ctx.elapsed_s = elapsed;
    ctx.rest_s = rest;
    ctx.region_share = valid_px_ > 0 ? static_cast<double>(valid_pixels(top_[i].footprint)) / valid_px_ : 0.0;
    ctx.region_px = static_cast<double>(valid_pixels(top_[i].footprint));
    if (inputs) {
      const cv::Rect region = region_rect(i);
      const CellInputs whole = inputs->cell(area_.valid_mask(region), cv::Rect(0, 0, region.width, region.height));
      ctx.region_input = whole.value(options_.cell_input);
      if (reads_field_entropy()) ctx.region_entropy = whole.value(DecisionInput::entropy);
    }
    ctx.lawnmowers = forecasts;
    rec.decision = policy_.decide(ctx);
    if (rec.decision.descend) {
      const std::size_t k = chosen_candidate(rec.decision, rec.candidates, policy_.name());
      ChosenDescent chosen{
          decisions_.size(),         i, rec.candidates[k].altitude_m, descents_chosen_++, std::move(sub_plans[k]),
          rec.candidates[k].deferred};
      if (rec.candidates[k].deferred) {
        tour_stops_.push_back(stops[k].first);
        tour_order_.insert(tour_order_.begin() + static_cast<std::ptrdiff_t>(stops[k].second.position), queued_.size());
        tour_images_ += chosen.plan.size();
        queued_.push_back(std::move(chosen));
      } else {
        start_descent(std::move(chosen));
      }
    }
    decisions_.push_back(rec);
    return rec;
  }

  /// Whether the budget still affords the rest of the descent in progress, from the image just
  /// reported: its remaining images and flight, then what follows it (the next top-level
  /// waypoint, or the rest of the tour being flown) and the rest of the mission, every image at
  /// the step bound. Cutting it here flies straight on to what follows.
  [[nodiscard]] bool descent_rest_fits() const {
    const double bound = step_bound();
    double inner = 0.0;  // from the image just reported through the descent's remaining waypoints
    for (std::size_t k = sub_next_; k < sub_.size(); ++k)
      inner += timing_.segment_time_s(sub_[k - 1].position, sub_[k].position);
    const double more_images = static_cast<double>(sub_.size() - sub_next_);
    // What follows: the rest of the tour being flown (none for a descent flown at once), its end,
    // and the top level from there on.
    std::vector<std::size_t> order;
    TourEnd end;
    std::size_t next_top = current_.top_index + 1;
    double after_images = 0.0, after_flight = 0.0;
    if (current_.deferred) {
      order.assign(tour_order_.begin() + static_cast<std::ptrdiff_t>(tour_next_), tour_order_.end());
      for (std::size_t k : order) after_images += static_cast<double>(queued_[k].plan.size());
      const std::size_t window_last = top_next_ - 1;
      end = tour_end(window_last);
      next_top = window_last + 1;
    } else {
      if (next_top < top_.size()) end = top_[next_top].position;
      if (schedule_.defers)
        after_flight += tour_extra_s(current_.top_index), after_images += static_cast<double>(tour_images_);
    }
    if (next_top < top_.size()) after_flight += flight_after_[next_top];
    after_images += static_cast<double>(top_.size() - std::min(next_top, top_.size()));
    const double go_on = inner + tour_flight_s(timing_, sub_.back().position, tour_stops_, order, end);
    const double mission_rest = after_flight + (more_images + after_images) * bound + (times_fixed() ? 0.0 : bound);
    return elapsed_s() + go_on + mission_rest <= *options_.budget_s + 1e-9;
  }

  /// The descent chosen at a top-level waypoint: its waypoints come next.
  void start_descent(ChosenDescent d) {
    sub_ = std::move(d.plan);
    sub_next_ = 0;
    current_ = std::move(d);
  }

  /// Tour: the next inspection of the tour comes next. Before the first, the tour is reordered
  /// (plan_tour_order: never longer than the order the decisions were charged for).
  void start_inspection() {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t i = top_next_ - 1;  // the window's last top-level waypoint
    if (tour_next_ == 0)
      tour_order_ = plan_tour_order(timing_, tour_start(i), tour_stops_, std::move(tour_order_), tour_end(i));
    start_descent(queued_[tour_order_[tour_next_++]]);
    charge_measured_planning(seconds_since(t0));
  }

  /// After a window's tour is flown: the next window's starts empty.
  void clear_tour() {
    queued_.clear();
    tour_stops_.clear();
    tour_order_.clear();
    tour_next_ = 0;
    tour_images_ = 0;
  }

  /// Where the tour of top-level waypoint i's window starts: the window's last top-level
  /// waypoint (DescentSchedule::tour: the survey's last; row: the row's last).
  [[nodiscard]] Eigen::Vector3d tour_start(std::size_t i) const { return top_[window_last_[i]].position; }
  /// Where it ends: the next window's first top-level waypoint (none after the survey's end).
  [[nodiscard]] TourEnd tour_end(std::size_t i) const {
    const std::size_t after = window_last_[i] + 1;
    return after < top_.size() ? TourEnd(top_[after].position) : std::nullopt;
  }
  /// What the tour chosen so far in top-level waypoint i's window adds to the top-level flight
  /// [s] (it replaces the direct leg from its start to its end).
  [[nodiscard]] double tour_extra_s(std::size_t i) const {
    if (tour_order_.empty()) return 0.0;
    const TourEnd end = tour_end(i);
    return tour_flight_s(timing_, tour_start(i), tour_stops_, tour_order_, end) -
           (end ? timing_.segment_time_s(tour_start(i), *end) : 0.0);
  }

  /// After a descent's last image: σ of the region at h' from the fused map, to the policy.
  DescentOutcome finish_descent() {
    DecisionRecord& rec = decisions_[current_.decision];
    const std::size_t top_index = current_.top_index;
    DescentOutcome out;
    out.top_altitude_m = top_[top_index].position.z();
    out.sub_altitude_m = current_.altitude_m;
    out.descent = current_.ordinal;
    out.sigma_top = rec.sigma;
    const cv::Rect region = region_rect(top_index);
    out.sigma_sub = region.area() == 0
                        ? 0.0
                        : semantic_ratio(map_.labels()(region), options_.mission.interest, map_.unknown_label());
    if (region.area() > 0)
      out.relabelled =
          relabelling(descent_before_, map_.labels()(region), area_.valid_mask(region), options_.mission.interest);
    if (coverage_.ranks_cells) {
      const Candidate& chosen = rec.candidates[chosen_candidate(rec.decision, rec.candidates, policy_.name())];
      const double region_px = static_cast<double>(valid_pixels(top_[top_index].footprint));
      double top_mass = 0.0;  // over the cells flown (a descent cut short flew the first ones)
      for (std::size_t k = 0; k < chosen.cells.size() && k < sub_.size(); ++k)
        top_mass += chosen.cells[k].mass(options_.cell_input);
      if (region_px > 0.0) {
        out.top_input = top_mass / region_px;
        if (fine_known_) out.fine_input = fine_mass_ / region_px;
      }
    }
    out.cut_short = std::exchange(cut_short_, false);
    policy_.observe(out);
    rec.outcome = out;
    sub_.clear();
    sub_next_ = 0;
    return out;
  }

  CameraModel camera_;
  TimingModel timing_;
  SurveyArea area_;
  SemanticMap map_;
  Backend& backend_;
  Policy& policy_;
  AdaptiveOptions options_;
  const DescentScheduleInfo& schedule_;  ///< options_.schedule's
  const DescentCoverageInfo& coverage_;  ///< options_.coverage's
  std::vector<double> candidates_;
  double top_gsd_cm_ = 0.0;  ///< the GSD the top level is flown at
  std::vector<Waypoint> top_;
  std::vector<double> flight_after_;  ///< flight time of the top-level plan from waypoint i on [s]
  /// A fixed-altitude lawnmower over the area (a front-aware policy's yardstick).
  struct LawnmowerCost {
    double gsd_cm = 0.0;
    double flight_s = 0.0;
    std::size_t images = 0;
  };
  std::vector<LawnmowerCost> lawnmowers_;  ///< at the candidate and top GSDs
  double valid_px_ = 0.0;                  ///< field pixels of the whole map grid

  std::size_t top_next_ = 0;   ///< next top-level waypoint to hand out
  std::vector<Waypoint> sub_;  ///< the descent in progress, if any
  std::size_t sub_next_ = 0;   ///< next waypoint of sub_ to hand out
  ChosenDescent current_;      ///< the descent in progress (its plan moved to sub_)
  std::size_t descents_chosen_ = 0;
  cv::Mat descent_before_;    ///< the region's map before the descent in progress
  double fine_mass_ = 0.0;    ///< ranked: Σ over its images so far of the finer look's input mass
  bool fine_known_ = true;    ///< ... every image of it gave the input
  bool cut_short_ = false;    ///< the budget ended the descent in progress early
  GridInputs region_inputs_;  ///< the last top-level image's inputs (buffers reused)
  GridInputs scene_inputs_;   ///< the last descent image's inputs over its cell (the scene check)
  /// Per top-level waypoint, the last top-level waypoint of its window: where the window's tour
  /// starts (DescentScheduleInfo::window_last).
  std::vector<std::size_t> window_last_;
  // A schedule that defers descents (DescentSchedule::tour, row): the tour of the window being flown.
  std::vector<ChosenDescent> queued_;    ///< every descent deferred in the window, in decision order
  std::vector<TourStop> tour_stops_;     ///< ... as tour stops (same order)
  std::vector<std::size_t> tour_order_;  ///< indices into queued_, in flight order
  std::size_t tour_next_ = 0;            ///< next of tour_order_ to fly
  std::size_t tour_images_ = 0;          ///< images of the queued descents
  bool pending_ = false;                 ///< path_.back() awaits its image
  std::vector<PlannedWaypoint> path_;
  std::vector<DecisionRecord> decisions_;

  double flight_s_ = 0.0;  ///< the planner's own time account [s]
  double segmentation_s_ = 0.0;
  double planning_s_ = 0.0;
  double slowest_segmentation_s_ = 0.0;
  double slowest_step_s_ = 0.0;           ///< the largest advance of the clock beyond a leg's flight [s]
  double elapsed_at_last_image_s_ = 0.0;  ///< elapsed_s() when the last image was reported
  std::size_t steps_ = 0;                 ///< images reported
  double untaken_planning_s_ = 0.0;
  std::optional<double> reported_elapsed_s_;
};

}  // namespace adaptseg
