// Times the ensemble backend against its members, side by side in one run: per round, K
// segment() calls of each member (OnnxSegmenter, as the ensemble runs it: with test-time
// mirror where its `mirror` says so, and then also without), then K of the ensemble (EnsembleSegmenter:
// every member, the weighted mean, its argmax) and K of segment_with_disagreement() (the same
// plus disagreement and class splits), on one 480x360 camera image of held-out Dubai tile 6
// at 2x its GSD; medians over all rounds. One OpenCV thread count per run.
//
//   bench_ensemble ENSEMBLE_DIR FIELD_DIR [--threads N] [--rounds R] [--iters K]
//
// Prints a markdown table row per backend: name, threads, median [ms].

#include "bench_timing.hpp"

#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <cstdio>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: bench_ensemble ENSEMBLE_DIR FIELD_DIR [--threads N] [--rounds R] [--iters K]\n";
    return 2;
  }
  int threads = 2, rounds = 5, iters = 5;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const int v = std::stoi(argv[i + 1]);
    if (a == "--threads")
      threads = v;
    else if (a == "--rounds")
      rounds = v;
    else if (a == "--iters")
      iters = v;
    else {
      std::cerr << "bench_ensemble: unknown option " << a << '\n';
      return 2;
    }
  }
  try {
    const auto field = adaptseg::Field::load(argv[2]);
    const adaptseg::CameraModel camera;
    adaptseg::OnnxParams p{.resize_to_network = true, .num_threads = threads};
    adaptseg::EnsembleSegmenter ensemble(argv[1], field, camera, p);
    std::vector<adaptseg::OnnxSegmenter> members;
    std::vector<std::string> names;
    for (const auto& m : ensemble.member_list()) {
      const std::string name = m.model_dir.filename().string();
      adaptseg::OnnxParams pm = p;
      pm.test_time_mirror = m.mirror;
      members.emplace_back(m.model_dir, field, camera, pm);
      names.push_back(name + (m.mirror ? " (member, with mirror)" : " (member)"));
      if (m.mirror) {
        members.emplace_back(m.model_dir, field, camera, p);
        names.push_back(name + " (alone, one pass)");
      }
    }
    const auto plan = adaptseg::LawnmowerPlanner(camera).plan(field.area(), 2.0 * field.gsd_cm());
    const adaptseg::Image image = adaptseg::SimulatedSensor(field, camera).capture(plan.at(plan.size() / 2));
    std::vector<std::vector<double>> member_ms(members.size());
    std::vector<double> ens_ms, dis_ms;
    for (auto& m : members) (void)m.segment(image);  // warm-up
    (void)ensemble.segment_with_disagreement(image);
    // Rounds interleave the backends; each round's times join the backend's sample.
    const auto time_into = [&](std::vector<double>& sample, auto&& f) {
      const std::vector<double> t = adaptseg::bench::time_ms(f, 0, iters);
      sample.insert(sample.end(), t.begin(), t.end());
    };
    for (int r = 0; r < rounds; ++r) {
      for (std::size_t k = 0; k < members.size(); ++k)
        time_into(member_ms[k], [&] { (void)members[k].segment(image); });
      time_into(ens_ms, [&] { (void)ensemble.segment(image); });
      time_into(dis_ms, [&] { (void)ensemble.segment_with_disagreement(image); });
    }
    const auto median = [](const std::vector<double>& v) { return adaptseg::bench::stats(v).median; };
    for (std::size_t k = 0; k < members.size(); ++k)
      std::printf("| %s | %d | %.1f |\n", names[k].c_str(), threads, median(member_ms[k]));
    std::printf("| ensemble segment() | %d | %.1f |\n", threads, median(ens_ms));
    std::printf("| ensemble segment_with_disagreement() | %d | %.1f |\n", threads, median(dis_ms));
  } catch (const std::exception& e) {
    std::cerr << "bench_ensemble: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
