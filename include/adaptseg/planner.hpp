#pragma once
/// @file
/// Umbrella header of everything CMake target adaptseg::vision gives: the core
/// (<adaptseg/core.hpp>: camera, flight time, lawnmower planner, Gaussian process, decision rules)
/// and the vision component (<adaptseg/vision.hpp>: fields, sensor, oracle, map, metrics, missions,
/// the adaptive planner, calibration). The components with further dependencies have their own
/// umbrella header and CMake target: <adaptseg/erfnet.hpp> (adaptseg::erfnet, OpenCV DNN),
/// <adaptseg/geo.hpp> (adaptseg::geo, GeographicLib) and <adaptseg/gdal.hpp> (adaptseg::gdal).

#include <adaptseg/vision.hpp>
