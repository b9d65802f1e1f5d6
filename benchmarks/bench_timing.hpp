#pragma once
// Wall-clock timing of a callable and the statistics the benchmarks print (bench_erfnet,
// bench_ensemble). Not part of the library.

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <vector>

namespace adaptseg::bench {

/// Median, minimum and maximum of a sample.
struct Stats {
  double median = 0.0, min = 0.0, max = 0.0;
};

/// Stats of `v` (non-empty).
inline Stats stats(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  const double med = n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  return {med, v.front(), v.back()};
}

/// `warmup` untimed calls of `f`, then `iters` timed ones [ms].
template <typename F>
std::vector<double> time_ms(F&& f, int warmup, int iters) {
  for (int i = 0; i < warmup; ++i) f();
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(iters));
  for (int i = 0; i < iters; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const auto t1 = std::chrono::steady_clock::now();
    out.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  return out;
}

}  // namespace adaptseg::bench
