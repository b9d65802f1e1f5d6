// Time of one per-waypoint decision (GP predictions for every candidate altitude) of the
// DecisionFunction, for O/I sizes seen in practice and after many online updates.
//   build/release/benchmarks/bench_decision
#include <adaptseg/decision_function.hpp>
#include <adaptseg/lawnmower_curve.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

int main() {
  using namespace adaptseg;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<Candidate> candidates{{1.0, 5.5, 9, 36.0}, {1.5, 8.25, 4, 20.0}, {2.0, 11.0, 4, 19.0},
                                          {2.5, 13.75, 4, 19.0}};
  const std::vector<LawnmowerForecast> lawnmowers{{1.0, 185.0}, {1.5, 107.0}, {2.0, 101.0}, {2.5, 96.0}, {3.0, 39.0}};
  std::printf("| rule | initial samples | online updates | decision (4 candidates) median [us] | p99 [us] |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: |\n");
  for (int n : {28, 100, 400}) {
    std::vector<RegionSample> samples;
    for (int k = 0; k < n; ++k) {
      RegionSample s;
      s.delta_h_m = 2.75 * (1 + k % 4);
      s.sigma_top = 0.3 * u(rng);
      s.sigma_sub = s.sigma_top * (1.0 + 0.05 * s.delta_h_m) + 0.01 * u(rng);
      s.miou_top = 0.7 + 0.05 * u(rng);
      s.miou_sub = s.miou_top + 0.02 * s.delta_h_m + 0.02 * u(rng);
      samples.push_back(s);
    }
    // The paper's rule with the paper's I, and the programs' default: front-aware with I on (Δσ, Δh).
    for (const bool front_aware : {false, true})
    for (int updates : {0, 100}) {
      const auto inputs = front_aware ? DecisionFunction::GainInputs::delta_sigma_and_height
                                      : DecisionFunction::GainInputs::delta_sigma;
      DecisionFunction df = DecisionFunction::initialize(samples, {.front_aware = front_aware}, 1, 0, inputs);
      df.set_reference_lawnmower({{1.0, 1.0}, {1.5, 0.85}, {2.0, 0.82}, {2.5, 0.77}, {3.0, 0.75}});
      for (int k = 0; k < updates; ++k)
        df.observe({16.5, 5.5 + 2.75 * (k % 4), 0.3 * u(rng), 0.3 * u(rng)});
      std::vector<double> us;
      for (int rep = 0; rep < 2000; ++rep) {
        DecisionContext c{.sigma = 0.3 * u(rng), .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5,
                          .candidates = candidates, .elapsed_s = 40.0 * u(rng), .rest_s = 20.0,
                          .region_share = 1.0 / 7.0, .lawnmowers = lawnmowers};
        if (rep % 7 == 0) df.reset_mission();
        const auto t0 = std::chrono::steady_clock::now();
        const Decision d = df.decide(c);
        const auto t1 = std::chrono::steady_clock::now();
        if (d.scores.size() != candidates.size()) return 1;
        us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      }
      std::sort(us.begin(), us.end());
      std::printf("| %s | %d | %d | %.1f | %.1f |\n", front_aware ? "front-aware, I(dsigma, dh)" : "utility threshold, I(dsigma)", n, updates, us[us.size() / 2], us[us.size() * 99 / 100]);
    }
  }
  return 0;
}
