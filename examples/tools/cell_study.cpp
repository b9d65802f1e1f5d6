// adaptseg_cell_study: how well each decision input, known at the top level, ranks the cells a
// descent could re-map by what re-mapping them gains (docs/results.md, "Cells").
//
// For each field and label of interest: the top-level lawnmower over the whole field is flown
// and fused; then, for each top-level region and each candidate GSD, every cell of the region's
// sub-lawnmower is flown, and its realised gain is the field IoU of the top-level map with only
// that cell's pixels re-mapped, minus the top-level map's. Per (field, class, GSD) it prints,
// for every input of the table in include/adaptseg/core/decision_inputs.hpp, the rank correlation of
// the cells' input mass (value x field pixels) with their gain and the share of the achievable
// positive gain that re-mapping the top 10 % / 20 % of cells by that mass captures, beside a
// random choice and the best possible (hindsight), and their means over the groups; with --decision-model,
// the mean capture of the input that model's planner ranks cells by. --csv writes every cell.
//
//   adaptseg_cell_study --field examples/data/dubai-tile-4 --field examples/data/dubai-tile-6
//       --classes building,road,vegetation,water --segmenter network
//       --network examples/models/mobilenetv2-dubai --csv out/cells.csv

#include "common/cell_csv.hpp"
#include "common/host_memory.hpp"
#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/grid_inputs.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <optional>

namespace {

using namespace adaptseg;

/// One cell of one region's sub-lawnmower at one GSD, for one class.
struct Cell {
  std::string field;
  std::string cls;
  std::size_t region = 0;
  double gsd_cm = 0.0;
  CellInputs top;            ///< decision inputs of the top-level image over the cell
  CellInputs fine;           ///< the same quantities from the finer image over the cell
  double field_share = 0.0;  ///< the cell's field pixels / the field's
  double field_sigma = 0.0;  ///< σ of the class over the field's top-level map
  double relabelled = 0.0;   ///< share of the cell's field pixels relabelled with the class involved
  double gain = 0.0;         ///< field IoU of the class with this cell re-mapped, minus without
};

/// Ranks of `v` (average ranks for ties), 1-based.
std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<std::size_t> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
    for (std::size_t k = i; k <= j; ++k) r[order[k]] = 0.5 * static_cast<double>(i + j) + 1.0;
    i = j + 1;
  }
  return r;
}

double spearman(const std::vector<double>& a, const std::vector<double>& b) {
  const auto ra = ranks(a), rb = ranks(b);
  const double n = static_cast<double>(a.size());
  const double ma = std::accumulate(ra.begin(), ra.end(), 0.0) / n, mb = std::accumulate(rb.begin(), rb.end(), 0.0) / n;
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (std::size_t k = 0; k < ra.size(); ++k) {
    sab += (ra[k] - ma) * (rb[k] - mb);
    saa += (ra[k] - ma) * (ra[k] - ma);
    sbb += (rb[k] - mb) * (rb[k] - mb);
  }
  return saa > 0.0 && sbb > 0.0 ? sab / std::sqrt(saa * sbb) : NAN;
}

/// Gain of the top `share` of cells ranked by `score` (descending; ties in cell order).
double top_gain(const std::vector<double>& score, const std::vector<double>& gain, double share) {
  std::vector<std::size_t> order(score.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return score[a] > score[b]; });
  const auto n = static_cast<std::size_t>(std::lround(share * static_cast<double>(score.size())));
  double g = 0.0;
  for (std::size_t k = 0; k < n && k < order.size(); ++k) g += gain[order[k]];
  return g;
}

/// Every cell of `field` for each class of `classes` (each alone as L).
template <class Backend>
std::vector<Cell> study_field(const Field& field, Backend& backend, const CameraModel& camera, double top_gsd,
                              const std::vector<double>& gsds, const std::vector<int>& classes) {
  const SimulatedSensor sensor(field, camera);
  const LawnmowerPlanner planner(camera);
  const int n = field.num_classes();
  const auto keep = [&](const Area& a) { return field.has_valid(a); };
  const auto tops = planner.plan(field.area(), top_gsd, {0.0, 0.0}, keep);
  SemanticMap top_map(field.labels().size(), field.ignore_label());
  std::vector<Image> images;
  std::vector<Segmentation> segs;
  for (const auto& w : tops) {
    images.push_back(sensor.capture(w));
    segs.push_back(segment_with_probabilities_checked(backend, images.back(), n));
    top_map.fuse(images.back(), segs.back().labels);
  }
  ConfusionMatrix field_cm(n);
  field_cm.add(field.labels(), top_map.labels(), field.ignore_label());
  const cv::Rect grid(0, 0, field.width_px(), field.height_px());
  std::vector<Cell> out;
  GridInputs fine_inputs;  // each finer image's over its cell (buffers reused)
  for (std::size_t t = 0; t < tops.size(); ++t) {
    const cv::Rect region = images[t].footprint_px & grid;
    const cv::Mat field_px = field.valid_mask()(region);
    // Each class's decision inputs over the region, summed cell by cell (GridInputs: the sums of
    // cell_inputs() of planes_on_grid() of pixel_inputs(), to the bit, without the planes).
    std::vector<GridInputs> top_inputs;  // per class
    for (int c : classes)
      top_inputs.emplace_back(images[t], segs[t], std::vector<int>{c}, field.ignore_label(), region,
                              kEveryDecisionInputList);
    for (double g : gsds) {
      const auto sub =
          planner.plan(tops[t].footprint, g, Eigen::Vector2d(tops[t].position.x(), tops[t].position.y()), keep);
      for (const auto& w : sub) {
        const Image img = sensor.capture(w);
        const Segmentation fine = segment_with_probabilities_checked(backend, img, n);
        // The cell's pixels inside the region: what a descent re-maps there (finer wins).
        const cv::Rect cell = field.pixel_rect(w.footprint) & region;
        if (cell.area() == 0) continue;
        SemanticMap local(region.size(), field.ignore_label());
        Image shifted = img;
        shifted.footprint_px -= region.tl();
        local.fuse(shifted, fine.labels);
        const cv::Rect cell_local = cell - region.tl();
        cv::Mat after = top_map.labels()(cell).clone();
        const cv::Mat fine_labels = local.labels()(cell_local);
        fine_labels.copyTo(after, fine_labels != field.ignore_label());
        ConfusionMatrix with = field_cm;
        {
          ConfusionMatrix before_cm(n), after_cm(n);
          before_cm.add(field.labels()(cell), top_map.labels()(cell), field.ignore_label());
          after_cm.add(field.labels()(cell), after, field.ignore_label());
          with -= before_cm;
          with += after_cm;
        }
        for (std::size_t k = 0; k < classes.size(); ++k) {
          const std::vector<int> l{classes[k]};
          Cell c;
          c.field = field.name();
          c.cls = field.classes()[static_cast<std::size_t>(classes[k])].name;
          c.region = t;
          c.gsd_cm = g;
          c.top = top_inputs[k].cell(field_px, cell_local);
          if (!(c.top.field_px > 0.0)) continue;
          fine_inputs.assign(shifted, fine, l, field.ignore_label(), cell_local, kEveryDecisionInputList,
                             GridInputs::Cells::one);
          c.fine = fine_inputs.cell(field_px(cell_local), cv::Rect(0, 0, cell.width, cell.height));
          c.field_share = c.top.field_px / std::max(1, field.valid_pixels());
          c.field_sigma = semantic_ratio(top_map.labels(), l, field.ignore_label());
          c.relabelled = relabelling(top_map.labels()(cell), after, field.valid_mask()(cell), l).interest_share;
          c.gain = with.miou(l).value_or(0.0) - field_cm.miou(l).value_or(0.0);
          out.push_back(std::move(c));
        }
      }
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  adaptseg::examples::keep_freed_memory();  // each mission's maps reuse the last one's pages
  CLI::App app{"How well each decision input ranks the cells a descent could re-map by what they gain.",
               "adaptseg_cell_study"};
  std::vector<std::string> field_specs;
  std::vector<std::string> class_names;
  std::vector<double> gsds{5.0};
  double top_gsd = 15.0;
  std::string csv_path;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::SegmenterOptions segmenter;
  app.add_option("--field", field_specs, "field DIR[:x0,y0,x1,y1]; repeatable")->required();
  app.add_option("--classes", class_names,
                 "classes to study, each alone as L, comma-separated (default: the field's interest)")
      ->delimiter(',');
  app.add_option("--top-gsd", top_gsd, "top-level GSD [cm/px]")->capture_default_str();
  app.add_option("--gsd", gsds, "candidate GSDs of the cells [cm/px], comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--csv", csv_path, "write every cell to this CSV file");
  std::filesystem::path decision_model;
  CLI::Option* model_opt = app.add_option(
      "--decision-model", decision_model,
      "a decision model calibrated with --coverage ranked: its input is the planner's ranking, summarised "
      "on its own line");
  adaptseg::examples::accept_old_spelling(app, model_opt, "--model", decision_model);
  common.add_to(app);
  segmenter.add_to(app);
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;
  try {
    std::optional<DecisionInput> planner_input;
    if (!decision_model.empty()) {
      const DecisionModel model = DecisionModel::load(decision_model);
      if (!model.decision_function.model().cells())
        throw std::invalid_argument("--decision-model " + decision_model.string() +
                                    " has no cell gain model (calibrate with --coverage ranked)");
      planner_input = model.decision_function.model().cells()->input();
    }
    std::vector<Cell> cells;
    for (const auto& spec : field_specs) {
      const Field field = adaptseg::examples::load_field_spec(spec);
      std::vector<int> classes = class_names.empty() ? field.interest() : field.class_indices(class_names);
      if (classes.empty())
        throw std::invalid_argument("field '" + field.name() + "' names no class of interest: pass --classes");
      const MissionOptions mo = common.resolve(field);
      const CameraModel camera(mo.camera);
      std::fprintf(stderr, "adaptseg_cell_study: %s ...\n", field.name().c_str());
      auto part = segmenter.with_backend(
          field, mo.camera, [&](auto& backend) { return study_field(field, backend, camera, top_gsd, gsds, classes); });
      cells.insert(cells.end(), part.begin(), part.end());
    }
    if (!csv_path.empty()) {
      std::ofstream os(csv_path);
      os << "field,class,region,gsd_cm,field_px,field_share,field_sigma,relabelled,gain";
      adaptseg::examples::write_input_columns_header(os);
      os << '\n';
      for (const Cell& c : cells) {
        os << adaptseg::examples::csv_field(c.field) << ',' << c.cls << ',' << c.region << ',' << c.gsd_cm << ','
           << c.top.field_px << ',' << c.field_share << ',' << c.field_sigma << ',' << c.relabelled << ',' << c.gain;
        adaptseg::examples::write_input_columns(os, c.top, c.fine);
        os << '\n';
      }
      if (!os) throw std::runtime_error("cannot write " + csv_path);
    }
    // The table: per field, class and GSD.
    std::printf("| field | class | GSD | cells | achievable | best 20 %% | random 20 %% |");
    for (const auto& in : kDecisionInputs) std::printf(" %s: rho / 10 %% / 20 %% |", std::string(in.name).c_str());
    std::printf("\n|---|---|---:|---:|---:|---:|---:|");
    for (std::size_t k = 0; k < kDecisionInputCount; ++k) std::printf("---|");
    std::printf("\n");
    std::vector<std::tuple<std::string, std::string, double>> groups;
    std::array<double, kDecisionInputCount> rho_sum{}, c10_sum{}, c20_sum{};
    std::array<int, kDecisionInputCount> counted{};
    double best_sum = 0.0, random_sum = 0.0;
    for (const Cell& c : cells)
      if (std::find(groups.begin(), groups.end(), std::tuple{c.field, c.cls, c.gsd_cm}) == groups.end())
        groups.emplace_back(c.field, c.cls, c.gsd_cm);
    for (const auto& [f, cls, g] : groups) {
      std::vector<double> gain;
      std::vector<std::vector<double>> mass(kDecisionInputCount);
      std::array<bool, kDecisionInputCount> known{};  // the backend gives the input (some cell has it)
      for (const Cell& c : cells) {
        if (c.field != f || c.cls != cls || c.gsd_cm != g) continue;
        gain.push_back(c.gain);
        for (std::size_t k = 0; k < kDecisionInputCount; ++k) {
          const double v = c.top.values[k];
          mass[k].push_back(std::isfinite(v) ? v * c.top.field_px : 0.0);
          known[k] = known[k] || std::isfinite(v);
        }
      }
      double positive = 0.0, total = 0.0;
      for (double x : gain) positive += std::max(0.0, x), total += x;
      std::printf("| %s | %s | %.1f | %zu | %.4f | %.2f | %.2f |", f.c_str(), cls.c_str(), g, gain.size(), positive,
                  positive > 0.0 ? top_gain(gain, gain, 0.2) / positive : NAN,
                  positive > 0.0 ? 0.2 * total / positive : NAN);
      for (std::size_t k = 0; k < kDecisionInputCount; ++k) {
        // An input the backend cannot give (e.g. the members' split of a single network) ranks
        // nothing: unknown, not the order the cells happen to come in.
        const double rho = known[k] ? spearman(mass[k], gain) : NAN;
        const double c10 = known[k] && positive > 0.0 ? top_gain(mass[k], gain, 0.1) / positive : NAN;
        const double c20 = known[k] && positive > 0.0 ? top_gain(mass[k], gain, 0.2) / positive : NAN;
        std::printf(" %+.2f / %.2f / %.2f |", rho, c10, c20);
        if (std::isfinite(rho) && std::isfinite(c20))
          rho_sum[k] += rho, c10_sum[k] += c10, c20_sum[k] += c20, ++counted[k];
      }
      if (positive > 0.0) best_sum += top_gain(gain, gain, 0.2) / positive, random_sum += 0.2 * total / positive;
      std::printf("\n");
    }
    // The means over the groups, and the planner's input.
    const int n = *std::max_element(counted.begin(), counted.end());
    std::printf("| mean | | | %d | | %.2f | %.2f |", n, n > 0 ? best_sum / n : NAN, n > 0 ? random_sum / n : NAN);
    for (std::size_t k = 0; k < kDecisionInputCount; ++k)
      std::printf(" %+.2f / %.2f / %.2f |", counted[k] ? rho_sum[k] / counted[k] : NAN,
                  counted[k] ? c10_sum[k] / counted[k] : NAN, counted[k] ? c20_sum[k] / counted[k] : NAN);
    std::printf("\n");
    if (planner_input) {
      const std::size_t k = index_of(*planner_input);
      std::printf(
          "\nthe planner's ranking (%s, from %s): mean capture of the achievable positive gain %.2f at 10 %% "
          "and %.2f at 20 %% of the cells (best possible at 20 %%: %.2f; random: %.2f)\n",
          to_string(*planner_input).c_str(), decision_model.string().c_str(),
          counted[k] ? c10_sum[k] / counted[k] : NAN, counted[k] ? c20_sum[k] / counted[k] : NAN,
          n > 0 ? best_sum / n : NAN, n > 0 ? random_sum / n : NAN);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_cell_study: error: %s\n", e.what());
    return 2;
  }
}
