// adaptseg_calibrate: initialise the decision function on training fields with ground truth
// (paper §3.2.2) and choose its settings there; writes the model for adaptseg_mission and
// adaptseg_evaluate.
//
//   adaptseg_calibrate --field examples/data/weedmap-000 --region 0,0,0.5,1 --segmenter oracle
//                      --out model.yaml
//   adaptseg_calibrate --train examples/data/dubai-tile-1 --train examples/data/dubai-tile-2:0,0,1,0.5
//                      --interest road --out roads.yaml
//   adaptseg_calibrate --field examples/data/dubai-tile-4 --segmenter network
//                      --network examples/models/ensemble-dubai --out ensemble-model.yaml

#include "common/cell_csv.hpp"
#include "common/host_memory.hpp"
#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <utility>

int main(int argc, char** argv) {
  adaptseg::examples::keep_freed_memory();  // each mission's maps reuse the last one's pages
  namespace fs = std::filesystem;
  CLI::App app{"Initialise the adaptive decision function on training fields and save it.", "adaptseg_calibrate"};
  fs::path field_dir, out_file, samples_csv, cell_samples_csv;
  std::string region_text;
  std::vector<std::string> train_specs;
  double top_factor = 3.0;
  std::vector<double> candidate_factors{1.0, 1.5, 2.0, 2.5};
  std::vector<double> lawnmower_factors{1.0, 1.5, 2.0, 2.5, 3.0};
  adaptseg::examples::CalibrationCli calibration;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::SegmenterOptions segmenter;  // the backend the missions will use
  CLI::Option* field_opt = app.add_option("--field", field_dir, "training field directory (with ground truth)");
  app.add_option("--region", region_text, "part of --field to use: x0,y0,x1,y1 in fractions along the image axes")
      ->needs(field_opt);
  app.add_option("--train", train_specs,
                 "training field DIR[:x0,y0,x1,y1]; repeatable (samples pooled, every field's lawnmower curve kept)")
      ->excludes(field_opt);
  app.add_option("--out", out_file, "model file to write (YAML)")->required();
  app.add_option("--samples-csv", samples_csv, "also write the region samples (one per region and candidate) here");
  CLI::Option* cells_opt = app.add_option(
      "--cell-samples-csv", cell_samples_csv,
      "also write the cell samples (--coverage ranked: one per cell of every top-level image and descent "
      "GSD, with every decision input the top-level and the finer image give it) here");
  bool frame_check = false;
  app.add_flag("--frame-check", frame_check,
               "fly each descent again with frames shifted half a footprint along its rows, and say in the cell "
               "samples which changes those frames make too (*_reframed columns; twice the segmentations)")
      ->needs(cells_opt);
  app.add_option("--top-factor", top_factor, "top-level GSD as a multiple of the field's GSD")->capture_default_str();
  app.add_option("--candidate-factors", candidate_factors, "candidate lower GSDs, multiples of the field's GSD")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--lawnmower-factors", lawnmower_factors,
                 "GSDs of the training lawnmower curves, multiples of the field's GSD")
      ->delimiter(',')
      ->capture_default_str();
  calibration.add_to(app);
  common.add_to(app);
  segmenter.add_to(app);
  segmenter.add_calibration_networks_to(app);
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;

  try {
    std::vector<adaptseg::Field> fields;
    if (!field_dir.empty()) {
      // As --train loads it: GeoTIFF fields too (built with GDAL), an empty region refused.
      if (!region_text.empty()) (void)adaptseg::examples::parse_region(region_text);  // its own message
      fields.push_back(adaptseg::examples::load_field_spec(
          region_text.empty() ? field_dir.string() : field_dir.string() + ":" + region_text));
    }
    for (const auto& spec : train_specs) fields.push_back(adaptseg::examples::load_field_spec(spec));
    if (fields.empty()) throw std::invalid_argument("give a training field: --field DIR or --train DIR (repeatable)");
    segmenter.validate();
    std::vector<std::size_t> grounds;
    const auto networks = segmenter.network_per_field(fields, &grounds);  // its mistakes before any work
    const adaptseg::Field& field = fields.front();
    const adaptseg::MissionOptions mission = common.resolve(field);
    const double g0 = field.gsd_cm();
    for (const auto& f : fields)
      if (f.gsd_cm() != g0)
        throw std::invalid_argument("training fields must share one GSD (the factors multiply it): '" + f.name() +
                                    "' has " + std::to_string(f.gsd_cm()) + " cm/px, '" + field.name() + "' " +
                                    std::to_string(g0));
    namespace ex = adaptseg::examples;
    ex::check_gsd_factors({top_factor}, "--top-factor");
    ex::check_gsd_factors(candidate_factors, "--candidate-factors");
    ex::check_gsd_factors(lawnmower_factors, "--lawnmower-factors");
    for (double f : candidate_factors)
      if (f >= top_factor)
        throw std::invalid_argument("--candidate-factors " + ex::fmt(f, 3) + " is not finer than --top-factor " +
                                    ex::fmt(top_factor, 3) + ": a descent must fly lower than the top level");
    adaptseg::CalibrationOptions options;
    options.adaptive.mission = mission;
    if (options.adaptive.mission.interest.empty()) options.adaptive.mission.interest = field.interest();
    options.adaptive.top_gsd_cm = top_factor * g0;
    for (double f : candidate_factors) options.adaptive.candidate_gsd_cm.push_back(f * g0);
    for (double f : lawnmower_factors) options.lawnmower_gsd_cm.push_back(f * g0);
    calibration.apply(options, common, g0);
    options.frame_check = frame_check;
    options.field_grounds = grounds;
    for (const auto& f : fields)
      std::fprintf(stderr, "calibrating on %s (%dx%d px, %.2f cm/px) with %s ...\n", f.name().c_str(), f.width_px(),
                   f.height_px(), g0, segmenter.name.c_str());
    const auto [cal, model] = segmenter.with_backend(field, mission.camera, [&](auto& backend) {
      adaptseg::CalibrationResult c =
          adaptseg::examples::calibrate_fields(segmenter, fields, networks, backend, options);
      adaptseg::DecisionModel m = adaptseg::make_decision_model(fields, backend.name(), options, c);
      return std::pair{std::move(c), std::move(m)};
    });
    if (out_file.has_parent_path()) fs::create_directories(out_file.parent_path());
    adaptseg::examples::print_field_segmenters(model);
    model.save(out_file);
    if (!samples_csv.empty()) {
      std::ostringstream os;
      os << "field,top_gsd_cm,sub_gsd_cm,delta_h_m,sigma_top,sigma_sub,miou_top,miou_sub,relabelled,"
            "relabelled_interest,region_share,field_sigma,field_gain,added_interest,removed_interest\n";
      for (const auto& s : cal.samples)
        os << adaptseg::examples::csv_field(fields[s.field].name()) << ',' << s.top_gsd_cm << ',' << s.sub_gsd_cm << ','
           << s.delta_h_m << ',' << s.sigma_top << ',' << s.sigma_sub << ',' << s.miou_top << ',' << s.miou_sub << ','
           << s.relabelled.share << ',' << s.relabelled.interest_share << ',' << s.region_share << ',' << s.field_sigma
           << ',' << s.field_gain << ',' << s.relabelled.added_share << ',' << s.relabelled.removed_share << '\n';
      adaptseg::examples::write_text(samples_csv, os.str());
    }
    if (!cell_samples_csv.empty()) {
      std::ostringstream os;
      os << "field,region,top_gsd_cm,sub_gsd_cm,field_px,field_share,field_sigma,relabelled,field_gain,delta_tp,"
            "delta_fp,field_tp,field_fp,field_fn,added,removed,added_right,removed_right,added_confirmed,"
            "removed_confirmed,added_confirmed_right,removed_confirmed_right,added_reframed,removed_reframed,"
            "added_reframed_right,removed_reframed_right";
      adaptseg::examples::write_input_columns_header(os);
      os << '\n';
      for (const auto& c : cal.cell_samples) {
        os << adaptseg::examples::csv_field(fields[c.field].name()) << ',' << c.region << ',' << c.top_gsd_cm << ','
           << c.sub_gsd_cm << ',' << c.top.field_px << ',' << c.field_share << ',' << c.field_sigma << ','
           << c.relabelled << ',' << c.field_gain << ',' << c.delta_tp << ',' << c.delta_fp << ',' << c.field_tp << ','
           << c.field_fp << ',' << c.field_fn << ',' << c.added << ',' << c.removed << ',' << c.right.added_share << ','
           << c.right.removed_share << ',' << c.confirmed.added_share << ',' << c.confirmed.removed_share << ','
           << c.confirmed_right.added_share << ',' << c.confirmed_right.removed_share << ',' << c.reframed.added_share
           << ',' << c.reframed.removed_share << ',' << c.reframed_right.added_share << ','
           << c.reframed_right.removed_share;
        adaptseg::examples::write_input_columns(os, c.top, c.fine);
        os << '\n';
      }
      adaptseg::examples::write_text(cell_samples_csv, os.str());
    }

    for (std::size_t k = 0; k < fields.size(); ++k) {
      std::printf("lawnmower curve of %s (time s, mIoU interest):", fields[k].name().c_str());
      for (const auto& p : cal.lawnmower_curves[k]) std::printf(" (%.1f, %.4f)", p.time_s, p.miou);
      std::printf("\n");
    }
    std::printf(
        "settings tried on the training fields, the chosen one first (time, mIoU and front margin: "
        "means over the fields flown; descents: all of them; then each field's front margin, in the "
        "order flown):\n");
    std::printf("  %-52s %9s %8s %13s %13s %8s  %s\n", "setting", "time [s]", "mIoU", "front margin", "worst margin",
                "descents", "per field");
    for (const auto& t : cal.trials) {
      std::printf("  %-52s %9.1f %8.4f %+13.4f %+13.4f %8d ", t.description.c_str(), t.time_s, t.miou_interest,
                  t.front_margin, t.worst_margin, t.descents);
      for (double m : t.margins) std::printf(" %+.4f", m);
      std::printf("\n");
    }
    if (!cal.cell_input_scores.empty()) {
      std::printf(
          "decision inputs tried for ranking the cells (share of the achievable gain the best 20 %% of the "
          "training fields' cells capture%s), the chosen one first:\n",
          options.cell_input_score == adaptseg::CellInputScore::transfer
              ? ", where the model fitted on the other fields forecasts a gain"
              : "");
      for (const auto& [input, score] : cal.cell_input_scores)
        std::printf("  %-16s %+.3f\n", adaptseg::to_string(input).c_str(), score);
      std::printf("%zu cell samples\n", cal.cell_samples.size());
      if (const auto& cells = cal.decision_function.model().cells()) {
        std::printf(
            "cell gain model of %s per pair of GSDs (gain slope beta; the scene check's proxy slope gamma "
            "and its spread between the training fields tau):\n",
            adaptseg::to_string(cells->input()).c_str());
        for (const auto& p : cells->points()) {
          std::printf("  %5.2f -> %5.2f cm/px  beta %+.3f  gamma %+.3f  tau %.3f", p.top_gsd_cm, p.sub_gsd_cm,
                      p.gain_slope, p.proxy_slope, p.proxy_slope_sd);
          if (p.entropy_slope != 0.0)  // field-entropy: beta at the reference entropy, and per unit of it
            std::printf("  (at entropy %.3f; %+.3f per unit, entropy %.3f to %.3f: beta %+.3f to %+.3f)",
                        p.entropy_reference, p.entropy_slope, p.entropy_low, p.entropy_high,
                        p.gain_slope_at(p.entropy_low), p.gain_slope_at(p.entropy_high));
          std::printf("\n");
        }
      }
    }
    std::printf("%zu region samples; linear sigma range [%.4f, %.4f]; model -> %s\n", cal.samples.size(),
                cal.linear.sigma_low, cal.linear.sigma_high, out_file.string().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_calibrate: error: %s\n", e.what());
    return 2;
  }
}
