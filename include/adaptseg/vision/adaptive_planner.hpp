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
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/time_account.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/detail/descent_costing.hpp>
#include <adaptseg/vision/detail/descent_in_progress.hpp>
#include <adaptseg/vision/detail/descent_tour.hpp>
#include <adaptseg/vision/detail/planner_checks.hpp>
#include <adaptseg/vision/detail/planner_clock.hpp>
#include <adaptseg/vision/detail/planner_route.hpp>
#include <adaptseg/vision/detail/region_summary.hpp>
#include <adaptseg/vision/detail/survey_grid.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/segment_and_report.hpp>
#include <adaptseg/vision/semantic_map.hpp>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <chrono>
#include <optional>
#include <utility>
#include <vector>

namespace adaptseg {

/// The adaptive planner run step by step (paper §3.2, Fig. workflow), for a caller that flies
/// the UAV and takes the images: a companion computer, or the simulation driver
/// run_adaptive_mission.
///
/// Protocol: `next()` gives the waypoint to fly to (nullopt when the mission is complete); the
/// caller flies there, takes the image and calls `report()` with it and its segmentation, once
/// (segment_and_report() with a backend). The planner checks it (once: CheckedSegmentation),
/// fuses it into its map and, at a top-level waypoint, decides: every descent over the region it
/// may fly (per candidate GSD its sub-lawnmower, descent_plan(); with ranked cells its best cells,
/// detail::RegionSummary) at its exact extra time (detail::DescentCosting: the detour minus the
/// leg it replaces, plus the per-image and per-waypoint estimates); those that would break the
/// budget are dropped and the policy chooses. A descent's waypoints come next, or
/// (DescentSchedule::tour / row) after the last top-level image of the survey / row, as one tour
/// with the other deferred descents. After its last image (detail::DescentInProgress) the
/// region's σ at h' and what it relabelled (from the fused map) go back to the policy (§3.2.3).
///
/// Time: the budget check uses the elapsed mission time the caller reports with each image,
/// or, if it reports none, the time account: the planner's own (flight by the timing model
/// along the planned waypoints; segmentation and planning measured, or fixed per image /
/// waypoint), or one it shares with the caller (run_adaptive_mission: the Mission's).
///
/// Holds a reference to `policy`, which must outlive the planner. It holds no backend: what
/// crosses into it is each image's segmentation, checked once.
///
/// @code
/// adaptseg::AdaptivePlanner planner(area, policy, options);
/// while (const auto w = planner.next()) {
///   const cv::Mat bgr = fly_and_shoot(w->waypoint.position);         // the UAV's part
///   const auto step = adaptseg::segment_and_report(planner, backend, planner.image_at(measured_pose(), bgr));
///   if (step.decision && step.decision->decision.descend) { /* a sub-lawnmower comes (next) */ }
/// }
/// const adaptseg::SemanticMap& map = planner.map();
/// @endcode
template <DecisionPolicy Policy>
class AdaptivePlanner {
 public:
  /// Plans the top-level lawnmower over `area` (cells without field skipped). `shared`: a time
  /// account to charge planning into and read the mission time from, whose owner charges
  /// flight and segmentation (a Mission's; not null: it must outlive the planner).
  /// @throws std::invalid_argument for an invalid area (num_classes not set included), camera
  ///         or timing, no labels of interest (or one that is not a class index), a top GSD
  ///         finer than the map's, candidates that are not finer than the top (or none to
  ///         descend to), a budget that is not positive, or one too small for the top-level
  ///         coverage alone.
  AdaptivePlanner(SurveyArea area, Policy& policy, AdaptiveOptions options, TimeAccount* shared = nullptr)
      : grid_(std::move(area), CameraModel(options.mission.camera), options.grid_anchor, options.descent_grid),
        timing_(options.mission.timing),
        map_(grid_.size(), grid_.area().ignore_label, options.mission.map_fusion, options.mission.interest),
        policy_(policy),
        options_(std::move(options)),
        coverage_(descent_coverage_info(options_.coverage)),
        clock_(options_.mission, shared) {
    const auto t0 = std::chrono::steady_clock::now();
    policy_.begin_mission();
    candidates_ = detail::planner_candidates(options_, grid_.area());

    // The area's lawnmowers at the candidate and top GSDs (what the mission could fly instead;
    // planned as run_lawnmower_mission plans them), for front-aware policies.
    std::vector<double> lawnmower_gsds = candidates_;
    lawnmower_gsds.push_back(options_.top_gsd_cm);
    lawnmowers_ = detail::LawnmowerCosts(grid_, timing_, lawnmower_gsds);
    // The top level: the options' top GSD, or another of the lawnmower GSDs where the policy
    // chooses one (ChoosesTopLevel); descents go to the candidates finer than it.
    top_gsd_cm_ = detail::choose_top_gsd(policy_, lawnmowers_, lawnmower_forecasts(), options_.top_gsd_cm, candidates_);
    route_ = detail::PlannerRoute(grid_.lawnmower(top_gsd_cm_), descent_schedule_info(options_.schedule), timing_);
    clock_.charge_planning(detail::seconds_since(t0));
    detail::check_top_level_budget(options_.budget_s, route_.flight_after(0), route_.top().size(),
                                   clock_.per_image_estimate());
  }

  /// The next waypoint to fly to and take an image at; the same one again while its image has
  /// not been reported; nullopt once the mission is complete.
  [[nodiscard]] std::optional<PlannedWaypoint> next() {
    if (pending_) return path_.back();
    // A tour starts once the last top-level waypoint of its window (the survey, or the row) is
    // flown; once flown, it is cleared for the next window's.
    if (!descent_.has_next() && !route_.tour().taken() && top_next_ > 0 &&
        top_next_ - 1 == route_.window_last(top_next_ - 1))
      start_inspection();
    if (!descent_.has_next() && top_next_ < route_.top().size() && route_.tour().started() && route_.tour().taken())
      route_.tour().clear();
    PlannedWaypoint p;
    if (descent_.has_next()) {
      descent_.hand_out(p);
    } else if (top_next_ < route_.top().size()) {
      p.waypoint = route_.top()[top_next_];
      p.top_index = top_next_++;
    } else {
      return std::nullopt;
    }
    p.index = path_.size();
    path_.push_back(p);
    pending_ = true;
    clock_.waypoint_handed_out();
    return p;
  }

  /// Reports the image taken at the pending waypoint with its segmentation `labels`, which
  /// took `segmentation_s` [s] (ignored when the options fix a segmentation time). The image's
  /// pose (`position`, `footprint_px`, `yaw_deg`) is what gets fused: the waypoint's, or the
  /// one the UAV measured (see image_at()). `elapsed_s`: the mission time [s] the caller
  /// measured up to now, used for the budget instead of the time account. Nothing changes
  /// when it throws: the waypoint stays pending.
  /// segment_and_report() segments the image with a backend and reports it.
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
  /// without), checked here (CheckedSegmentation::check()).
  /// @throws std::invalid_argument as the labels overload, and for probabilities (member votes)
  ///         that break their contract (check_probabilities()).
  PlannerStep report(const Image& image, const Segmentation& segmentation, double segmentation_s,
                     std::optional<double> elapsed_s = std::nullopt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_report(image, elapsed_s);
    const CheckedSegmentation checked =
        detail::check_reported_segmentation(segmentation, image, grid_.area().num_classes);
    return accept_checked(image, checked, segmentation_s, elapsed_s, t0);
  }

  /// As the other overloads, for a segmentation checked where it was made (segment_and_check():
  /// a backend's, checked once) for this image and the area's class set.
  /// @throws std::invalid_argument as the labels overload, and for a segmentation checked for
  ///         another image size, ignore label or class set.
  PlannerStep report(const Image& image, const CheckedSegmentation& segmentation, double segmentation_s,
                     std::optional<double> elapsed_s = std::nullopt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_report(image, elapsed_s);
    detail::require(segmentation.checked_for(image, grid_.area().num_classes),
                    "AdaptivePlanner::report: the segmentation was checked for another image size, ignore label or "
                    "class set",
                    grid_.area().num_classes);
    return accept_checked(image, segmentation, segmentation_s, elapsed_s, t0);
  }

  /// Throws what report() throws before it reads the segmentation: nothing pending, an image
  /// not of the camera's size, without footprint or with a yaw that is not finite, an elapsed
  /// time that is negative or not finite (segment_and_report() asks before it segments).
  void check_report(const Image& image, std::optional<double> elapsed_s) const {
    detail::check_reported_image(image, grid_.camera(), pending_, path_.size(), elapsed_s);
  }

  /// Whether the planner reads the class probabilities behind each image's labels: for the decision
  /// inputs of a coverage that ranks cells, and for a pooled map (which refuses labels alone).
  [[nodiscard]] bool wants_probabilities() const noexcept {
    return coverage_.ranks_cells || pools_probabilities(map_.fusion());
  }

  /// The Image of a camera frame `bgr` (CV_8UC3, B, G, R of the camera's size, or empty) taken at
  /// `pose`: x, y [m] in the field frame, z the altitude above ground [m]. Nadir camera whose
  /// image x axis is turned `yaw_deg` counter-clockwise from the field's x axis (Image::yaw_deg;
  /// 0: the plan's heading); the GSD follows from the altitude, the footprint is centred under
  /// the camera, snapped to map pixels as SimulatedSensor does, and turned by the yaw when fused.
  /// @throws std::invalid_argument for a pose or yaw that is not finite or an altitude <= 0,
  ///         and a colour image of another size or type.
  [[nodiscard]] Image image_at(const Eigen::Vector3d& pose, cv::Mat bgr = {}, double yaw_deg = 0.0) const {
    return grid_.image_at(pose, std::move(bgr), yaw_deg);
  }

  /// The sub-lawnmower that re-maps the region of top-level waypoint `top_index` at `gsd_cm`
  /// (paper §3.2.1 W^{h'}): its grid laid as AdaptiveOptions::grid_anchor says (from the region's
  /// corner nearest that waypoint, or centred on the region), or with DescentGrid::field the
  /// cells of the area's lawnmower at `gsd_cm` centred in the region, visited from the corner
  /// nearest the waypoint, cells without field skipped.
  /// @throws std::invalid_argument for an index out of range or a GSD that is not positive.
  [[nodiscard]] std::vector<Waypoint> sub_plan(std::size_t top_index, double gsd_cm) const {
    detail::require(top_index < route_.top().size(), "AdaptivePlanner::sub_plan: top_index out of range", top_index);
    return grid_.sub_lawnmower(route_.top()[top_index], gsd_cm);
  }

  /// The sub-lawnmower a descent at top-level waypoint `top_index` flies at `gsd_cm` once the
  /// region's top-level image is fused: sub_plan() with the cells `options().coverage` flies
  /// (DescentCoverageInfo::flies, given the region's map; DescentCoverage::interest: only the
  /// cells whose ground, grown by one top-level pixel and clipped to the region, shows a label of
  /// interest; visiting order unchanged). A coverage that ranks cells offers subsets of it.
  /// @throws std::invalid_argument as sub_plan().
  [[nodiscard]] std::vector<Waypoint> descent_plan(std::size_t top_index, double gsd_cm) const {
    if (!coverage_.flies) return sub_plan(top_index, gsd_cm);
    detail::require(top_index < route_.top().size(), "AdaptivePlanner::descent_plan: top_index out of range",
                    top_index);
    const cv::Rect region = region_rect(top_index);
    const cv::Mat labels = map_.labels()(region);
    const auto keep_cell = [&](const Area& a) {
      return valid_pixels(a) > 0 && coverage_.flies(labels, pixel_rect(a) - region.tl(), top_gsd_cm_,
                                                    grid_.area().map_gsd_cm, options_.mission.interest);
    };
    return grid_.sub_lawnmower(route_.top()[top_index], gsd_cm, keep_cell);
  }

  /// The map pixels of top-level waypoint `top_index`'s region: its footprint, clipped to the map grid.
  /// @throws std::out_of_range for an index out of range.
  [[nodiscard]] cv::Rect region_rect(std::size_t top_index) const {
    return pixel_rect(route_.top().at(top_index).footprint) & grid_.rect();
  }

  /// The waypoints of the descent in progress, in visiting order: decided at the last
  /// top-level image, or (DescentSchedule::tour / row) the inspection being flown; empty when
  /// none is in progress or decided.
  [[nodiscard]] const std::vector<Waypoint>& descent() const noexcept { return descent_.waypoints(); }

  /// The top-level lawnmower W^{h_max}.
  [[nodiscard]] const std::vector<Waypoint>& top_level() const noexcept { return route_.top(); }
  /// The GSD it is flown at [cm/px]: the options' top GSD, or the policy's choice (ChoosesTopLevel).
  [[nodiscard]] double top_gsd_cm() const noexcept { return top_gsd_cm_; }
  /// The candidate GSDs a descent may fly [cm/px] (those not finer than the map, finer than
  /// the top level).
  [[nodiscard]] const std::vector<double>& candidate_gsd_cm() const noexcept { return candidates_; }
  /// Every waypoint next() may hand out: the top level and, per region, every candidate's
  /// sub-lawnmower (what a pre-recorded image set must cover).
  [[nodiscard]] std::vector<Waypoint> reachable_waypoints() const {
    std::vector<Waypoint> out = route_.top();
    for (std::size_t i = 0; i < route_.top().size(); ++i)
      for (double g : candidates_) {
        const auto sub = sub_plan(i, g);
        out.insert(out.end(), sub.begin(), sub.end());
      }
    return out;
  }

  /// True once every waypoint has been handed out and reported.
  [[nodiscard]] bool done() const noexcept {
    return !pending_ && !descent_.has_next() && top_next_ >= route_.top().size() && route_.tour().taken();
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
  [[nodiscard]] const SurveyArea& area() const noexcept { return grid_.area(); }
  [[nodiscard]] const CameraModel& camera() const noexcept { return grid_.camera(); }
  [[nodiscard]] const TimingModel& timing() const noexcept { return timing_; }
  [[nodiscard]] const AdaptiveOptions& options() const noexcept { return options_; }

  /// Mission time so far [s]: what the caller reported with the last image if it did,
  /// otherwise the time account's (flight + segmentation + planning).
  [[nodiscard]] double elapsed_s() const noexcept { return clock_.elapsed_s(); }

  /// Measured planner computation [s] since the last call (planning the top level, decisions,
  /// online updates): what a caller keeping its own time account charges as planning time.
  [[nodiscard]] double take_planning_s() noexcept { return clock_.take_planning_s(); }

  /// The pixels of the map grid under `a` (raster_rect, as Field::pixel_rect); may extend
  /// beyond the grid.
  [[nodiscard]] cv::Rect pixel_rect(const Area& a) const { return grid_.pixel_rect(a); }

  /// Field pixels of the map grid under `a`.
  [[nodiscard]] int valid_pixels(const Area& a) const { return grid_.valid_pixels(a); }

  /// Share of the ground under `a` that is field (paper: DecisionContext::valid_fraction).
  [[nodiscard]] double valid_fraction(const Area& a) const { return grid_.valid_fraction(a); }

 private:
  /// The checks of a report that follow the segmentation's (its time, a pooled map's
  /// probabilities), then accept(); both report() overloads of a segmentation end here.
  PlannerStep accept_checked(const Image& image, const CheckedSegmentation& segmentation, double segmentation_s,
                             std::optional<double> elapsed_s, std::chrono::steady_clock::time_point t0) {
    detail::check_segmentation_time(segmentation_s);
    detail::check_pooled(map_.fusion(), segmentation.get(), "none were reported");
    return accept(image, segmentation.get(), segmentation_s, elapsed_s, t0);
  }

  /// A reported image and its checked labels: the time account, the fused map, and at a
  /// top-level waypoint the decision, after a descent's last image its outcome. The planner's
  /// processing since `t0` is charged as planning time.
  PlannerStep accept(const Image& image, const Segmentation& segmentation, double segmentation_s,
                     std::optional<double> elapsed_s, std::chrono::steady_clock::time_point t0) {
    const cv::Mat& labels = segmentation.labels;
    pending_ = false;
    const PlannedWaypoint& p = path_.back();
    const double leg =
        p.index > 0 ? timing_.segment_time_s(path_[p.index - 1].waypoint.position, p.waypoint.position) : 0.0;
    clock_.image_reported(leg, segmentation_s, elapsed_s);
    PlannerStep step;
    step.waypoint = p;
    step.sigma = semantic_ratio(labels, options_.mission.interest, image.ignore_label);
    if (p.level == 1) {  // the region before the descent, the policy's guard; with ranked cells, the scene check
      const cv::Rect region = region_rect(p.top_index);
      const cv::Rect cell = pixel_rect(p.waypoint.footprint) & region;
      step.trusted = detail::trusts_descent_image(policy_, map_, cell, options_.mission.interest, step.sigma);
      descent_.see(p.step, step.trusted, map_.labels()(region), image, segmentation,
                   coverage_.ranks_cells ? std::optional(options_.cell_input) : std::nullopt, cell,
                   options_.mission.interest, grid_.area().ignore_label, grid_.area().valid_mask);
    }
    if (step.trusted) map_.fuse(image, segmentation);
    // A budget that can no longer afford the rest of the descent ends it here.
    if (p.level == 1) descent_.cut_short_unless_it_fits(costing(), top_next_);
    if (p.level == 0)
      step.decision = decide(p, step.sigma, image, segmentation);
    else if (!descent_.has_next())
      step.outcome = finish_descent();
    clock_.charge_planning(detail::seconds_since(t0));
    return step;
  }

  /// The area's lawnmowers at the candidate and nominal top GSDs with their forecast times:
  /// flight plus the per-image segmentation and planning estimates.
  [[nodiscard]] std::vector<LawnmowerForecast> lawnmower_forecasts() const {
    return lawnmowers_.forecasts(clock_.per_image_estimate());
  }

  /// Descent costing (descent_costing.hpp) over the planner's route, clock and budget.
  [[nodiscard]] detail::DescentCosting costing() const {
    return {route_, timing_, clock_, grid_.camera(), options_.budget_s};
  }

  /// The decision at top-level waypoint `p` (paper §3.2.2), its candidates with exact costs; a
  /// descent chosen comes next, or (deferred) goes into the window's tour.
  DecisionRecord decide(const PlannedWaypoint& p, double sigma, const Image& image, const Segmentation& segmentation) {
    const std::size_t i = p.top_index;
    DecisionRecord rec;
    rec.waypoint_index = p.index;
    rec.sigma = sigma;
    // Time still needed after this waypoint's decision to finish the top-level coverage (and
    // the tour chosen so far: what it adds to the top-level legs).
    const detail::PlannerRoute::Ahead ahead = route_.ahead(timing_, i);
    const double rest = ahead.flight_s + ahead.images * clock_.per_image_estimate();
    const cv::Rect region = region_rect(i);
    const bool entropy = detail::reads_field_entropy(policy_);
    const GridInputs* inputs = coverage_.ranks_cells
                                   ? summary_.inputs(image, segmentation, region, options_.mission.interest,
                                                     grid_.area().ignore_label, options_.cell_input, entropy)
                                   : nullptr;
    std::vector<detail::CostedPlan> plans = costing().cost(
        detail::RegionSummary::options(grid_, region, candidates_, coverage_.ranks_cells, inputs, options_.cell_input,
                                       options_.gain_extent, [&](double g) { return descent_plan(i, g); }),
        i, ahead, rec);
    const std::vector<LawnmowerForecast> forecasts = lawnmower_forecasts();
    const detail::DecisionInputsAt at{route_.top()[i], region, inputs, options_.cell_input, entropy};
    rec.decision = policy_.decide(detail::decision_context(grid_, at, top_gsd_cm_, rec, elapsed_s(), rest, forecasts));
    if (rec.decision.descend) {
      const std::size_t k = chosen_candidate(rec.decision, rec.candidates, policy_.name());
      detail::ChosenDescent chosen{
          decisions_.size(),         i, rec.candidates[k].altitude_m, descents_chosen_++, std::move(plans[k].plan),
          rec.candidates[k].deferred};
      if (rec.candidates[k].deferred)
        route_.tour().add(std::move(chosen), plans[k].stop, plans[k].insertion.position);
      else
        descent_.start(std::move(chosen));
    }
    decisions_.push_back(rec);
    return rec;
  }

  /// Tour: the next inspection of the tour comes next. Before the first, the tour is reordered
  /// (plan_tour_order: never longer than the order the decisions were charged for).
  void start_inspection() {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t i = top_next_ - 1;  // the window's last top-level waypoint
    descent_.start(route_.tour().take_next(timing_, route_.tour_start(i), route_.tour_end(i)));
    clock_.charge_planning(detail::seconds_since(t0));
  }

  /// After a descent's last image: σ of the region at h' from the fused map and what the
  /// descent relabelled (with ranked cells, the input over the cells flown), to the policy.
  DescentOutcome finish_descent() {
    DecisionRecord& rec = decisions_[descent_.chosen().decision];
    const Waypoint& top = route_.top()[descent_.chosen().top_index];
    const detail::DescentRegion region{map_.labels(),
                                       grid_.area().valid_mask,
                                       region_rect(descent_.chosen().top_index),
                                       static_cast<double>(valid_pixels(top.footprint)),
                                       options_.mission.interest,
                                       map_.unknown_label()};
    const Candidate* chosen = coverage_.ranks_cells
                                  ? &rec.candidates[chosen_candidate(rec.decision, rec.candidates, policy_.name())]
                                  : nullptr;
    const DescentOutcome out = descent_.finish(region, rec.sigma, top.position.z(), chosen, options_.cell_input);
    policy_.observe(out);
    rec.outcome = out;
    return out;
  }

  detail::SurveyGrid grid_;  ///< the area, its field and the camera's lawnmowers over it
  TimingModel timing_;
  SemanticMap map_;
  Policy& policy_;
  AdaptiveOptions options_;
  const DescentCoverageInfo& coverage_;  ///< options_.coverage's
  detail::PlannerClock clock_;           ///< the time account
  std::vector<double> candidates_;
  double top_gsd_cm_ = 0.0;            ///< the GSD the top level is flown at
  detail::PlannerRoute route_;         ///< the top-level lawnmower, its windows and their tours
  detail::LawnmowerCosts lawnmowers_;  ///< the area's lawnmowers at the candidate and top GSDs (a yardstick)

  std::size_t top_next_ = 0;           ///< next top-level waypoint to hand out
  detail::DescentInProgress descent_;  ///< the descent being flown, if any
  std::size_t descents_chosen_ = 0;
  detail::RegionSummary summary_;  ///< the last top-level image's region as the decision read it
  bool pending_ = false;           ///< path_.back() awaits its image
  std::vector<PlannedWaypoint> path_;
  std::vector<DecisionRecord> decisions_;
};

}  // namespace adaptseg
