#pragma once
/// @file
/// Umbrella header of the sim component (CMake target adaptseg::sim; vision's dependencies): the
/// experiment layer, the strategies a mission flies in simulation and the flight of one of them,
/// a backend that segments each image once (CachedBackend), and the table of a mission's
/// decisions (decisions.csv).

#include <adaptseg/sim/cached_backend.hpp>
#include <adaptseg/sim/csv.hpp>
#include <adaptseg/sim/decision_table.hpp>
#include <adaptseg/sim/strategy.hpp>
