#pragma once
/// @file
/// Umbrella header of the GDAL component (CMake target adaptseg::gdal, defined where GDAL 3.1 or
/// later is found): GeoTIFF fields in, georeferenced maps out, survey sites, their plans (inside
/// the site, terrain from a DEM, sorties) and pictures, and where a picture says it was taken
/// (EXIF GPS).

#include <adaptseg/gdal/elevation_model.hpp>
#include <adaptseg/gdal/exif_position.hpp>
#include <adaptseg/gdal/gdal_io.hpp>
#include <adaptseg/gdal/map_geotiff.hpp>
#include <adaptseg/gdal/site_fence.hpp>
#include <adaptseg/gdal/site_lawnmower.hpp>
#include <adaptseg/gdal/site_picture.hpp>
#include <adaptseg/gdal/site_plan.hpp>
#include <adaptseg/gdal/survey_site.hpp>
