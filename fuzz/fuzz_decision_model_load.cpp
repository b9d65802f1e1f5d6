// Fuzz target: DecisionModel::load on an arbitrary file (the YAML of adaptseg_calibrate
// --out, with the decision function's text and both GPs embedded).

#include "fuzz_support.hpp"

#include <adaptseg/vision/decision_model.hpp>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = adaptseg::fuzz::scratch_dir() / "model.yaml";
  adaptseg::fuzz::write_bytes(file, data, size);
  adaptseg::fuzz::expect_clean([&] { (void)adaptseg::DecisionModel::load(file); });
  return 0;
}
