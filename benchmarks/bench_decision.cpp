// Time of one per-waypoint decision (GP predictions for every candidate altitude) of the
// paper's utility rule and of the front-aware rule, for sample counts seen in practice and
// after many online updates.
//   build/release/benchmarks/bench_decision
#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/core/utility_policy.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

int main() {
  using namespace adaptseg;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<Candidate> candidates{
      {1.0, 5.5, 9, 36.0}, {1.5, 8.25, 4, 20.0}, {2.0, 11.0, 4, 19.0}, {2.5, 13.75, 4, 19.0}};
  const std::vector<LawnmowerForecast> lawnmowers{{1.0, 185.0}, {1.5, 107.0}, {2.0, 101.0}, {2.5, 96.0}, {3.0, 39.0}};
  const std::vector<ReferenceCurve> reference{
      {"a", {{1.0, 1.0}, {1.5, 0.85}, {2.0, 0.82}, {2.5, 0.77}, {3.0, 0.75}}, 0.1},
      {"b", {{1.0, 1.0}, {1.5, 0.88}, {2.0, 0.84}, {2.5, 0.80}, {3.0, 0.78}}, 0.2}};
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
      s.relabelled = {0.15 * s.sigma_top, 0.1 * s.sigma_top * (0.5 + u(rng))};
      s.region_share = 0.1;
      s.field_sigma = 0.15;
      s.field_gain = s.delta_h_m / 11.0 * s.relabelled.interest_share * s.region_share / s.field_sigma;
      samples.push_back(s);
    }
    // The paper's rule with the paper's I, and the programs' default: front-aware.
    const GainModel paper = GainModel::fit(samples, {.gain_inputs = GainModel::GainInputs::delta_sigma, .restarts = 1});
    const GainModel model = GainModel::fit(samples, {.restarts = 1});
    for (const bool front_aware : {false, true})
      for (int updates : {0, 100}) {
        UtilityPolicy utility(paper, {});
        FrontAwarePolicy front(model, reference, {.confidence = 1.0});
        const auto time_rule = [&](auto& policy) {
          policy.begin_mission();
          for (int k = 0; k < updates; ++k)
            policy.observe({16.5, 5.5 + 2.75 * (k % 4), 0.3 * u(rng), 0.3 * u(rng), {0.02 * u(rng), 0.01 * u(rng)}});
          std::vector<double> us;
          for (int rep = 0; rep < 2000; ++rep) {
            DecisionContext c{.sigma = 0.3 * u(rng),
                              .valid_fraction = 1.0,
                              .top_gsd_cm = 3.0,
                              .top_altitude_m = 16.5,
                              .candidates = candidates,
                              .elapsed_s = 40.0 * u(rng),
                              .rest_s = 20.0,
                              .region_share = 1.0 / 7.0,
                              .lawnmowers = lawnmowers};
            const auto t0 = std::chrono::steady_clock::now();
            const Decision d = policy.decide(c);
            const auto t1 = std::chrono::steady_clock::now();
            if (d.scores.size() != candidates.size()) return std::vector<double>{};
            us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
          }
          std::sort(us.begin(), us.end());
          return us;
        };
        const std::vector<double> us = front_aware ? time_rule(front) : time_rule(utility);
        if (us.empty()) return 1;
        std::printf("| %s | %d | %d | %.1f | %.1f |\n",
                    front_aware ? "front-aware (O, I, C; 2 reference curves)" : "utility threshold, I(dsigma)", n,
                    updates, us[us.size() / 2], us[us.size() * 99 / 100]);
      }
  }
  return 0;
}
