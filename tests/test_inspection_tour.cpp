#include <adaptseg/core/inspection_tour.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

using namespace adaptseg;

namespace {
const TimingModel timing{};  // v = 2 m/s, a = 2 m/s²

// Stops like a mission's sub-lawnmowers: entry somewhere over a 120 x 100 m field at 27.5 m,
// exit up to 30 m away, inner flight of their legs; the tour starts at 82.5 m.
std::vector<TourStop> random_stops(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> x(0.0, 120.0), y(0.0, 100.0), d(-30.0, 30.0), inner(5.0, 60.0);
  std::vector<TourStop> s(n);
  for (auto& stop : s) {
    stop.entry = {x(rng), y(rng), 27.5};
    stop.exit = stop.entry + Eigen::Vector3d(d(rng), d(rng), 0.0);
    stop.inner_flight_s = inner(rng);
  }
  return s;
}

// Each stop inserted where it adds least, in the order chosen (as the planner builds a tour).
std::vector<std::size_t> insertion_order(const Eigen::Vector3d& start, const std::vector<TourStop>& stops) {
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < stops.size(); ++k) {
    const TourInsertion ins = cheapest_insertion(timing, start, stops, order, stops[k]);
    order.insert(order.begin() + static_cast<std::ptrdiff_t>(ins.position), k);
  }
  return order;
}

// The insertion order improved by the local search.
std::vector<std::size_t> heuristic(const Eigen::Vector3d& start, const std::vector<TourStop>& stops) {
  return improve_tour_order(timing, start, stops, insertion_order(start, stops));
}
}  // namespace

TEST_CASE("inspection tour: a tour's time is its legs plus its stops' inner flights") {
  // Start at the origin; stop A from x = 10 to 20, stop B from x = 30 to 40 (all at z = 0).
  const std::vector<TourStop> s{{{10, 0, 0}, {20, 0, 0}, 7.0}, {{30, 0, 0}, {40, 0, 0}, 9.0}};
  const Eigen::Vector3d start(0, 0, 0);
  const std::vector<std::size_t> ab{0, 1}, ba{1, 0};
  CHECK(tour_flight_s(timing, start, s, ab) ==
        doctest::Approx(timing.segment_time_s(10.0) + 7.0 + timing.segment_time_s(10.0) + 9.0));
  CHECK(tour_flight_s(timing, start, s, ba) ==
        doctest::Approx(timing.segment_time_s(30.0) + 9.0 + timing.segment_time_s(30.0) + 7.0));
  CHECK(tour_flight_s(timing, start, s, std::vector<std::size_t>{}) == 0.0);
  CHECK(optimal_tour_order(timing, start, s) == ab);
  CHECK(plan_tour_order(timing, start, s, ba) == ab);
  CHECK_THROWS_AS((void)tour_flight_s(timing, start, s, std::vector<std::size_t>{2}), std::invalid_argument);
}

TEST_CASE("inspection tour: cheapest insertion adds exactly what the tour grows by, at the best place") {
  std::mt19937 rng(7);
  const Eigen::Vector3d start(60, 50, 82.5);
  for (int trial = 0; trial < 50; ++trial) {
    auto stops = random_stops(rng, 6);
    const TourStop extra = stops.back();
    stops.pop_back();
    const std::vector<std::size_t> order{3, 0, 4, 1, 2};
    const double before = tour_flight_s(timing, start, stops, order);
    const TourInsertion ins = cheapest_insertion(timing, start, stops, order, extra);
    stops.push_back(extra);
    double best = 1e300;
    for (std::size_t p = 0; p <= order.size(); ++p) {
      auto o = order;
      o.insert(o.begin() + static_cast<std::ptrdiff_t>(p), 5);
      const double t = tour_flight_s(timing, start, stops, o);
      if (p == ins.position) CHECK(t - before == doctest::Approx(ins.added_s).epsilon(1e-12));
      best = std::min(best, t);
    }
    CHECK(before + ins.added_s == doctest::Approx(best).epsilon(1e-12));
  }
}

TEST_CASE("inspection tour: the exact order is the best of every permutation") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(0.0, 120.0), y(0.0, 100.0);
  for (std::size_t n = 0; n <= 7; ++n)
    for (int trial = 0; trial < 10; ++trial) {
      const auto stops = random_stops(rng, n);
      const Eigen::Vector3d start(x(rng), y(rng), 82.5);
      std::vector<std::size_t> order(n);
      std::iota(order.begin(), order.end(), std::size_t{0});
      double brute = tour_flight_s(timing, start, stops, order);
      while (std::next_permutation(order.begin(), order.end()))
        brute = std::min(brute, tour_flight_s(timing, start, stops, order));
      const auto exact = optimal_tour_order(timing, start, stops);
      CAPTURE(n);
      CHECK(exact.size() == n);
      CHECK(tour_flight_s(timing, start, stops, exact) == doctest::Approx(brute).epsilon(1e-12));
    }
  CHECK_THROWS_AS((void)optimal_tour_order(timing, Eigen::Vector3d::Zero(), random_stops(rng, kExactTourStops + 1)),
                  std::invalid_argument);
}

TEST_CASE("inspection tour: the local search against the optimum (its gap, measured)") {
  // Tours of 2-12 stops: insertion order improved by 2-opt and or-opt against the exact order.
  // The gap is printed (run with -s) and quoted in docs/method.md.
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> x(0.0, 120.0), y(0.0, 100.0);
  int optimal = 0, trials = 0;
  double gap_sum = 0.0, gap_max = 0.0;
  for (std::size_t n = 2; n <= kExactTourStops; ++n)
    for (int trial = 0; trial < 20; ++trial) {
      const auto stops = random_stops(rng, n);
      const Eigen::Vector3d start(x(rng), y(rng), 82.5);
      const auto h = heuristic(start, stops);
      auto sorted = h;
      std::sort(sorted.begin(), sorted.end());
      std::vector<std::size_t> all(n);
      std::iota(all.begin(), all.end(), std::size_t{0});
      CHECK(sorted == all);  // a permutation of the stops
      const double th = tour_flight_s(timing, start, stops, h);
      const double to = tour_flight_s(timing, start, stops, optimal_tour_order(timing, start, stops));
      CHECK(th >= to - 1e-9);
      const double gap = th / to - 1.0;
      optimal += gap < 1e-9 ? 1 : 0;
      gap_sum += gap;
      gap_max = std::max(gap_max, gap);
      ++trials;
    }
  MESSAGE("local search vs optimum over ", trials, " random tours of 2-", kExactTourStops, " stops: optimal in ",
          optimal, ", mean gap ", 100.0 * gap_sum / trials, " %, worst ", 100.0 * gap_max, " %");
  CHECK(optimal >= trials / 2);
  CHECK(gap_max < 0.10);
}

TEST_CASE("inspection tour: the planned order is never longer than the insertion order") {
  std::mt19937 rng(5);
  const Eigen::Vector3d start(0, 0, 82.5);
  for (std::size_t n : {std::size_t{1}, std::size_t{5}, kExactTourStops, std::size_t{20}, std::size_t{40}}) {
    const auto stops = random_stops(rng, n);
    const auto inserted = insertion_order(start, stops);
    const auto planned = plan_tour_order(timing, start, stops, inserted);
    CAPTURE(n);
    CHECK(planned.size() == n);
    CHECK(tour_flight_s(timing, start, stops, planned) <= tour_flight_s(timing, start, stops, inserted) + 1e-9);
    if (n <= kExactTourStops)
      CHECK(tour_flight_s(timing, start, stops, planned) ==
            doctest::Approx(tour_flight_s(timing, start, stops, optimal_tour_order(timing, start, stops))));
  }
}

TEST_CASE("inspection tour: a tour with a fixed end (a row's tour, up to the next row) prices its last leg") {
  // From the origin, A at (10, 0) and B at (0, 12) (z = 0): open, A then B (10 + 15.6 m of
  // legs) beats B then A (12 + 15.6); to an end at (20, 0), B then A (12 + 15.6 + 10) beats
  // A then B (10 + 15.6 + 23.3): the end turns the order round.
  const std::vector<TourStop> s{{{10, 0, 0}, {10, 0, 0}, 4.0}, {{0, 12, 0}, {0, 12, 0}, 4.0}};
  const Eigen::Vector3d start(0, 0, 0), end(20, 0, 0);
  const std::vector<std::size_t> ab{0, 1}, ba{1, 0};
  CHECK(tour_flight_s(timing, start, s, ab, end) ==
        doctest::Approx(tour_flight_s(timing, start, s, ab) + timing.segment_time_s(s[1].exit, end)));
  CHECK(tour_flight_s(timing, start, s, std::vector<std::size_t>{}, end) ==
        doctest::Approx(timing.segment_time_s(start, end)));
  CHECK(optimal_tour_order(timing, start, s) == ab);
  CHECK(optimal_tour_order(timing, start, s, end) == ba);
  CHECK(plan_tour_order(timing, start, s, ab, end) == ba);

  // Insertion, exact order and local search against brute force, with an end.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> x(0.0, 120.0), y(0.0, 100.0);
  for (std::size_t n = 1; n <= 6; ++n)
    for (int trial = 0; trial < 10; ++trial) {
      auto stops = random_stops(rng, n);
      const Eigen::Vector3d from(x(rng), y(rng), 82.5), to(x(rng), y(rng), 82.5);
      // Cheapest insertion of the last stop adds exactly what the best tour through it grows by.
      const TourStop extra = stops.back();
      stops.pop_back();
      std::vector<std::size_t> order(stops.size());
      std::iota(order.begin(), order.end(), std::size_t{0});
      const double before = tour_flight_s(timing, from, stops, order, to);
      const TourInsertion ins = cheapest_insertion(timing, from, stops, order, extra, to);
      stops.push_back(extra);
      auto grown = order;
      grown.insert(grown.begin() + static_cast<std::ptrdiff_t>(ins.position), n - 1);
      CHECK(tour_flight_s(timing, from, stops, grown, to) - before == doctest::Approx(ins.added_s).epsilon(1e-12));
      for (std::size_t p = 0; p <= order.size(); ++p) {
        auto o = order;
        o.insert(o.begin() + static_cast<std::ptrdiff_t>(p), n - 1);
        CHECK(tour_flight_s(timing, from, stops, o, to) >= before + ins.added_s - 1e-9);
      }
      // The exact order is the best permutation; the planned one never longer than the insertion's.
      std::vector<std::size_t> all(n);
      std::iota(all.begin(), all.end(), std::size_t{0});
      double brute = tour_flight_s(timing, from, stops, all, to);
      while (std::next_permutation(all.begin(), all.end()))
        brute = std::min(brute, tour_flight_s(timing, from, stops, all, to));
      CAPTURE(n);
      CHECK(tour_flight_s(timing, from, stops, optimal_tour_order(timing, from, stops, to), to) ==
            doctest::Approx(brute).epsilon(1e-12));
      CHECK(tour_flight_s(timing, from, stops, plan_tour_order(timing, from, stops, grown, to), to) <=
            tour_flight_s(timing, from, stops, grown, to) + 1e-9);
      CHECK(tour_flight_s(timing, from, stops, improve_tour_order(timing, from, stops, grown, to), to) <=
            tour_flight_s(timing, from, stops, grown, to) + 1e-9);
    }
}
