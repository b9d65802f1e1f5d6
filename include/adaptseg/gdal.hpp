#pragma once
/// @file
/// Umbrella header of the GDAL component (CMake target adaptseg::gdal, defined where GDAL 3.1 or
/// later is found): GeoTIFF fields in, georeferenced maps out, and survey sites.

#include <adaptseg/gdal/gdal_io.hpp>
#include <adaptseg/gdal/survey_site.hpp>
