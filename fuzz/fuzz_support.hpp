#pragma once
// Shared by the fuzz targets: a private scratch directory, and the rule that decides what is
// a finding. A loader may reject any input, but only with the library's documented
// exception types: std::invalid_argument, std::runtime_error and its subclasses
// (adaptseg::NumericalError). A YAML::Exception (a yaml-cpp error the loader failed to
// wrap; it derives from std::runtime_error, so it is checked first) or any other exception
// is a finding: the harness aborts and libFuzzer records the input.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

namespace adaptseg::fuzz {

/// A directory of this process's own under the system temp dir, created on first use.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("adaptseg-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

inline void write_bytes(const std::filesystem::path& file, const std::uint8_t* data, std::size_t size) {
  std::ofstream os(file, std::ios::binary | std::ios::trunc);
  os.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!os) std::abort();  // the harness's own failure, not the loader's
}

[[noreturn]] inline void finding(const char* kind, const char* what) {
  std::fprintf(stderr, "FINDING: %s escaped the loader: %s\n", kind, what);
  std::abort();
}

/// Runs `load`; returns normally if it succeeds or throws a documented type, aborts otherwise.
template <typename F>
void expect_clean(F&& load) {
  try {
    load();
  } catch (const YAML::Exception& e) {
    finding("YAML::Exception", e.what());
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {
  } catch (const std::exception& e) {
    finding("an undocumented std::exception", e.what());
  } catch (...) {
    finding("a non-std exception", "?");
  }
}

}  // namespace adaptseg::fuzz
