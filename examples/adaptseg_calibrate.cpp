// adaptseg_calibrate: initialise the decision function on a training field with ground truth
// (paper §3.2.2) and choose its thresholds there; writes the model for adaptseg_mission and
// adaptseg_evaluate.
//
//   adaptseg_calibrate --field examples/data/weedmap-000 --region 0,0,0.5,1 --segmenter oracle
//                      --out model.yaml
//   adaptseg_calibrate --field examples/data/dubai-tile-4 --segmenter erfnet
//                      --model-file examples/models/erfnet-dubai --out erfnet-model.yaml

#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <cstdio>
#include <filesystem>
#include <utility>

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  CLI::App app{"Initialise the adaptive decision function on a training field and save it."};
  fs::path field_dir, out_file;
  std::string region_text;
  double top_factor = 3.0;
  std::vector<double> candidate_factors{1.0, 1.5, 2.0, 2.5};
  std::vector<double> lawnmower_factors{1.0, 1.5, 2.0, 2.5, 3.0};
  adaptseg::examples::CalibrationCli calibration;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::SegmenterOptions segmenter;  // the backend the missions will use
  app.add_option("--field", field_dir, "training field directory (with ground truth)")->required();
  app.add_option("--region", region_text, "part of the field to use: x0,y0,x1,y1 in fractions along the image axes");
  app.add_option("--out", out_file, "model file to write (YAML)")->required();
  app.add_option("--top-factor", top_factor, "top-level GSD as a multiple of the field's GSD")->capture_default_str();
  app.add_option("--candidate-factors", candidate_factors, "candidate lower GSDs, multiples of the field's GSD")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--lawnmower-factors", lawnmower_factors,
                 "GSDs of the training lawnmower curve, multiples of the field's GSD")
      ->delimiter(',')
      ->capture_default_str();
  calibration.add_to(app);
  common.add_to(app);
  segmenter.add_to(app);
  CLI11_PARSE(app, argc, argv);

  try {
    adaptseg::Field field = adaptseg::Field::load(field_dir);
    if (!region_text.empty()) field = field.sub_field(adaptseg::examples::parse_region(region_text));
    const adaptseg::MissionOptions mission = common.resolve(field);
    const double g0 = field.gsd_cm();
    adaptseg::CalibrationOptions options;
    options.adaptive.mission = mission;
    if (options.adaptive.mission.interest.empty()) options.adaptive.mission.interest = field.interest();
    options.adaptive.top_gsd_cm = top_factor * g0;
    for (double f : candidate_factors) options.adaptive.candidate_gsd_cm.push_back(f * g0);
    for (double f : lawnmower_factors) options.lawnmower_gsd_cm.push_back(f * g0);
    calibration.apply(options);
    std::fprintf(stderr, "calibrating on %s (%dx%d px, %.2f cm/px) with %s ...\n", field.name().c_str(),
                 field.width_px(), field.height_px(), g0, segmenter.name.c_str());
    const auto [cal, model] = segmenter.with_backend(field, mission.camera, [&](auto& backend) {
      adaptseg::CalibrationResult c = adaptseg::examples::calibrate_cached(field, backend, options);
      adaptseg::DecisionModel m = adaptseg::make_decision_model(field, backend.name(), options, c);
      return std::pair{std::move(c), std::move(m)};
    });
    if (out_file.has_parent_path()) fs::create_directories(out_file.parent_path());
    model.save(out_file);

    std::printf("training lawnmower curve (time s, mIoU interest):");
    for (const auto& p : cal.lawnmower_curve) std::printf(" (%.1f, %.4f)", p.time_s, p.miou);
    std::printf("\nthreshold trials (chosen first): weight_by_sigma relative front_aware min_utility -> time_s miou "
                "front_margin worst_margin descents\n");
    for (const auto& t : cal.trials)
      std::printf("  %d %d %d %.6g -> %.1f %.4f %+.4f %+.4f %d\n", t.params.weight_by_sigma ? 1 : 0,
                  t.params.relative_utility ? 1 : 0, t.params.front_aware ? 1 : 0, t.params.min_utility, t.time_s,
                  t.miou_interest, t.front_margin,
                  t.worst_margin, t.descents);
    std::printf("%zu region samples; linear sigma range [%.4f, %.4f]; model -> %s\n", cal.samples.size(),
                cal.linear.sigma_low, cal.linear.sigma_high, out_file.string().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_calibrate: error: %s\n", e.what());
    return 2;
  }
}
