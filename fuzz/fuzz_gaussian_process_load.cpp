// Fuzz target: the file reader of the Gaussian processes (both kernels; YAML, and the refusal
// of adaptseg 0.1's line format), from memory.

#include "fuzz_support.hpp"

#include <adaptseg/core/gaussian_process.hpp>
#include <adaptseg/vision/gp_io.hpp>

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  using namespace adaptseg;
  fuzz::expect_clean([&] {
    std::istringstream is(text);
    (void)load_gaussian_process<SquaredExponentialKernel>(is);
  });
  fuzz::expect_clean([&] {
    std::istringstream is(text);
    (void)load_gaussian_process<ArdSquaredExponentialKernel>(is);
  });
  return 0;
}
