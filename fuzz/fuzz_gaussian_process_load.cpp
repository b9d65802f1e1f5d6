// Fuzz target: the text loaders of the Gaussian processes (both kernels) and of the
// decision function of format-1 model files that embeds them, from memory.

#include "fuzz_support.hpp"

#include <adaptseg/decision_model.hpp>
#include <adaptseg/gaussian_process.hpp>

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  using namespace adaptseg;
  fuzz::expect_clean([&] {
    std::istringstream is(text);
    (void)GaussianProcess<SquaredExponentialKernel>::load(is);
  });
  fuzz::expect_clean([&] {
    std::istringstream is(text);
    (void)GaussianProcess<ArdSquaredExponentialKernel>::load(is);
  });
  fuzz::expect_clean([&] {
    std::istringstream is(text);
    (void)detail::read_legacy_decision_function(is, "fuzz");
  });
  return 0;
}
