#pragma once
/// @file
/// The library version; CMake parses it from here (the only place it is written).

#define ADAPTSEG_VERSION_MAJOR 0
#define ADAPTSEG_VERSION_MINOR 3
#define ADAPTSEG_VERSION_PATCH 0

namespace adaptseg {
/// Version as "MAJOR.MINOR.PATCH".
inline constexpr const char* kVersion = "0.3.0";
}  // namespace adaptseg
