// adaptseg_fit_temperature: the temperature T of a bundled network's probabilities
// softmax(logits / T), fitted on a validation field so that its confidence matches its accuracy,
// and the expected calibration error (ECE) per GSD band before (T = 1) and after.
//
// Every band is a whole-field lawnmower at that GSD (as adaptseg_evaluate flies them), each image
// segmented through the ONNX backend exactly as in a mission. A camera pixel's target is the
// share of each class among the orthomosaic pixels it covers (the ground-truth oracle's area
// vote, OracleSegmenter::segment_with_probabilities): T minimises the cross-entropy of the
// network's probabilities against it over every band's pixels (a grid of T, then golden section),
// and the ECE bins pixels by their largest probability (15 equal bins) and compares each bin's
// mean largest probability with the mean share of the predicted class: the accuracy at the
// orthomosaic's resolution. With --write the temperature is written into the model's model.yaml
// (key `temperature`, read by OnnxSegmenter); --set T writes a given one, nothing fitted (a
// temperature chosen elsewhere, e.g. the median of what networks of the same recipe fit on the
// tiles they never saw: scripts/loto.sh bundle).
//
//   adaptseg_fit_temperature --network examples/models/mobilenetv2-dubai
//       --field examples/data/dubai-tile-4 [--bands 1,1.5,2,2.5,3] [--threads 2] [--write]
//   adaptseg_fit_temperature --network DIR --set 1.25

#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace {

using namespace adaptseg;

constexpr int kBins = 15;

/// The pixels of one band's images: logits and the oracle's vote shares, per valid pixel.
struct Pixels {
  std::vector<float> logits;  ///< pixel-major, `classes` per pixel
  std::vector<float> target;  ///< the same layout: vote shares
  int classes = 0;
  [[nodiscard]] std::size_t size() const { return classes > 0 ? logits.size() / static_cast<std::size_t>(classes) : 0; }
};

/// Softmax of pixel k's logits over T into `p`.
void softmax(const Pixels& px, std::size_t k, double t, std::vector<double>& p) {
  const float* z = &px.logits[k * static_cast<std::size_t>(px.classes)];
  double m = z[0];
  for (int c = 1; c < px.classes; ++c) m = std::max(m, static_cast<double>(z[c]));
  double sum = 0.0;
  for (int c = 0; c < px.classes; ++c) sum += p[static_cast<std::size_t>(c)] = std::exp((z[c] - m) / t);
  for (int c = 0; c < px.classes; ++c) p[static_cast<std::size_t>(c)] /= sum;
}

/// Mean cross-entropy of the vote shares under softmax(logits / T).
double nll(const std::vector<Pixels>& bands, double t) {
  double s = 0.0;
  std::size_t n = 0;
  std::vector<double> p;
  for (const Pixels& px : bands) {
    p.resize(static_cast<std::size_t>(px.classes));
    for (std::size_t k = 0; k < px.size(); ++k) {
      softmax(px, k, t, p);
      for (int c = 0; c < px.classes; ++c) {
        const float v = px.target[k * static_cast<std::size_t>(px.classes) + static_cast<std::size_t>(c)];
        if (v > 0.0f) s -= v * std::log(std::max(p[static_cast<std::size_t>(c)], 1e-12));
      }
      ++n;
    }
  }
  return n > 0 ? s / static_cast<double>(n) : 0.0;
}

/// Expected calibration error: Σ_bins (pixels in bin / all) · |mean confidence − mean accuracy|.
double ece(const Pixels& px, double t) {
  std::array<double, kBins> conf{}, acc{}, count{};
  std::vector<double> p(static_cast<std::size_t>(px.classes));
  for (std::size_t k = 0; k < px.size(); ++k) {
    softmax(px, k, t, p);
    const auto best = static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin());
    const int bin = std::min(kBins - 1, static_cast<int>(p[best] * kBins));
    conf[static_cast<std::size_t>(bin)] += p[best];
    acc[static_cast<std::size_t>(bin)] += px.target[k * static_cast<std::size_t>(px.classes) + best];
    count[static_cast<std::size_t>(bin)] += 1.0;
  }
  double e = 0.0;
  const double n = static_cast<double>(px.size());
  for (int b = 0; b < kBins; ++b)
    if (count[static_cast<std::size_t>(b)] > 0.0)
      e += std::abs(conf[static_cast<std::size_t>(b)] - acc[static_cast<std::size_t>(b)]) / n;
  return e;
}

/// Writes `t` as the `temperature` of the network `model_file`'s model.yaml (replacing the key,
/// or appending it), the rest of the file as it was.
void write_temperature(const std::filesystem::path& model_file, double t) {
  if (!std::filesystem::exists(model_file))
    throw std::invalid_argument("--network " + model_file.string() + ": no such directory or file");
  const std::filesystem::path dir = std::filesystem::is_directory(model_file) ? model_file : model_file.parent_path();
  const std::filesystem::path yaml = dir / "model.yaml";
  std::ifstream in(yaml);
  if (!in) throw std::invalid_argument("cannot read " + yaml.string());
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  char line[64];
  std::snprintf(line, sizeof line, "temperature: %.4f", t);
  // Every line that starts with the key is replaced (a file has one); none: the key appended.
  std::string out;
  bool found = false;
  for (std::size_t at = 0; at < s.size();) {
    const std::size_t end = std::min(s.find('\n', at), s.size());
    const std::string_view row(s.data() + at, end - at);
    if (row.rfind("temperature:", 0) == 0) {
      out += line;
      found = true;
    } else {
      out += row;
    }
    if (end < s.size()) out += '\n';
    at = end + 1;
  }
  if (!found) out += (out.empty() || out.back() == '\n' ? "" : "\n") + std::string(line) + "\n";
  s = std::move(out);
  adaptseg::examples::write_text(yaml, s);
  std::printf("wrote %s to %s\n", line, yaml.string().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Fit a network's softmax temperature on a validation field; ECE per GSD band before and after.",
               "adaptseg_fit_temperature"};
  std::string field_spec;
  std::vector<double> bands{1.0, 1.5, 2.0, 2.5, 3.0};
  int stride = 3;
  bool write = false;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::SegmenterOptions segmenter;
  segmenter.name = "network";
  std::optional<double> set;
  app.add_option("--field", field_spec, "validation field DIR[:x0,y0,x1,y1] (not with --set)");
  app.add_option("--set", set, "no fit: write this temperature into the model's model.yaml")
      ->check(CLI::Range(0.01, 100.0));
  app.add_option("--bands", bands, "GSD bands as multiples of the field's GSD, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--pixel-stride", stride, "use every n-th camera pixel in x and y (speed)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_flag("--write", write, "write the fitted temperature into the model's model.yaml");
  std::optional<double> at;
  app.add_option("--at", at, "no fit: the ECE at this temperature (e.g. the model file's, on another field)")
      ->check(CLI::PositiveNumber);
  common.add_to(app);
  segmenter.add_to(app);
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;
  try {
    if (segmenter.name != "network")
      throw std::invalid_argument("--segmenter must be network: the oracle needs no temperature");
    if (set) {
      if (!field_spec.empty() || write || at)
        throw std::invalid_argument("--set writes a given temperature: no --field, --write or --at with it");
      segmenter.validate();
      write_temperature(segmenter.network, *set);
      return 0;
    }
    if (field_spec.empty()) throw std::invalid_argument("--field is required (the validation field to fit on)");
    if (at && write)
      throw std::invalid_argument("--at evaluates a given temperature; it cannot be combined with --write");
    const Field field = adaptseg::examples::load_field_spec(field_spec);
    adaptseg::examples::check_gsd_factors(bands, "--bands");
    const MissionOptions mo = common.resolve(field);
    const CameraModel camera(mo.camera);
    const SimulatedSensor sensor(field, camera);
    OracleSegmenter oracle(field.num_classes());
    std::vector<Pixels> per_band;
    segmenter.validate();
    if (adaptseg::EnsembleSegmenter::is_ensemble_dir(segmenter.network))
      throw std::invalid_argument("--network " + segmenter.network.string() +
                                  " is an ensemble: fit each member's temperature on its own folder");
    const auto [onnx, metadata] = adaptseg::network_files(segmenter.network);
    // Its logits, not AnyBackend's labels: the network itself, built as with_backend builds it.
    adaptseg::OnnxSegmenter net(onnx, metadata, segmenter.network_params(field, mo.camera));
    const double temperature_was = net.model_info().temperature;
    for (double f : bands) {
      Pixels px;
      px.classes = field.num_classes();
      const auto plan = LawnmowerPlanner(camera).plan(field.area(), f * field.gsd_cm(), {0.0, 0.0},
                                                      [&](const Area& a) { return field.has_valid(a); });
      for (const Waypoint& w : plan) {
        const Image img = sensor.capture(w);
        const std::vector<cv::Mat> logits = net.logits(img);
        const Segmentation truth = oracle.segment_with_probabilities(img);
        for (int y = 0; y < img.height_px; y += stride)
          for (int x = 0; x < img.width_px; x += stride) {
            if (truth.labels.at<unsigned char>(y, x) == img.ignore_label) continue;
            if (img.bgr.at<cv::Vec3b>(y, x) == cv::Vec3b(0, 0, 0)) continue;  // no data: not segmented
            for (int c = 0; c < px.classes; ++c) {
              px.logits.push_back(logits[static_cast<std::size_t>(c)].at<float>(y, x));
              px.target.push_back(truth.probabilities[static_cast<std::size_t>(c)].at<float>(y, x));
            }
          }
      }
      std::fprintf(stderr, "band %.2f cm/px: %zu images, %zu pixels\n", f * field.gsd_cm(), plan.size(), px.size());
      per_band.push_back(std::move(px));
    }
    // T: the best of a logarithmic grid over [0.25, 8], refined by golden section.
    double best = 1.0, best_nll = nll(per_band, 1.0);
    for (double t = 0.25; !at && t <= 8.0001; t *= 1.1) {
      const double v = nll(per_band, t);
      if (v < best_nll) best = t, best_nll = v;
    }
    double lo = best / 1.1, hi = best * 1.1;
    const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int k = 0; !at && k < 40; ++k) {
      const double a = hi - phi * (hi - lo), b = lo + phi * (hi - lo);
      if (nll(per_band, a) < nll(per_band, b))
        hi = b;
      else
        lo = a;
    }
    const double t = at ? *at : 0.5 * (lo + hi);
    std::printf("%s: %.4f (cross-entropy %.4f at T = 1, %.4f at T = %.4f; the model file has T = %.4f)\n",
                at ? "evaluated at" : "temperature", t, nll(per_band, 1.0), nll(per_band, t), t, temperature_was);
    std::printf("| GSD [cm/px] | pixels | ECE at T = 1 | ECE at T = %.2f |\n| ---: | ---: | ---: | ---: |\n", t);
    for (std::size_t b = 0; b < per_band.size(); ++b)
      std::printf("| %.1f | %zu | %.4f | %.4f |\n", bands[b] * field.gsd_cm(), per_band[b].size(),
                  ece(per_band[b], 1.0), ece(per_band[b], t));
    if (write) write_temperature(segmenter.network, t);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_fit_temperature: error: %s\n", e.what());
    return 2;
  }
}
