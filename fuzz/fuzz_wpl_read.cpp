// Fuzz target: read_wpl (the QGC WPL 110 plain-text waypoint format) on arbitrary text.

#include "fuzz_support.hpp"

#include <adaptseg/geo/wpl.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  adaptseg::fuzz::expect_clean([&] { (void)adaptseg::read_wpl(text); });
  return 0;
}
