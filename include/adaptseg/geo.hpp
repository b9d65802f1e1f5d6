#pragma once
/// @file
/// Umbrella header of the geo component (CMake target adaptseg::geo; GeographicLib, nlohmann_json):
/// a field's geo-reference, the export of a mission as a flyable plan, and its split into sorties.

#include <adaptseg/geo/export_path.hpp>
#include <adaptseg/geo/fence_route.hpp>
#include <adaptseg/geo/geojson.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/geo/mission_export.hpp>
#include <adaptseg/geo/qgc_plan.hpp>
#include <adaptseg/geo/sorties.hpp>
#include <adaptseg/geo/wpl.hpp>
