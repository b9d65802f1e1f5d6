#pragma once
/// @file
/// Umbrella header of the vision component (CMake target adaptseg::vision; OpenCV core, imgproc,
/// imgcodecs and yaml-cpp), with the core: images, labelled fields, the simulated sensor, the
/// oracle backend, the semantic map, metrics, missions, the adaptive planner, calibration and the
/// decision model's file.

#include <adaptseg/core.hpp>

#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/adaptive_planner.hpp>
#include <adaptseg/vision/any_backend.hpp>
#include <adaptseg/vision/calibration.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/decision_rules.hpp>
#include <adaptseg/vision/descent_coverage.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/field_geo.hpp>
#include <adaptseg/vision/front_aware_rule.hpp>
#include <adaptseg/vision/gain_extent.hpp>
#include <adaptseg/vision/gp_io.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/image_summary.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/mission.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/region_samples.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/semantic_map.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>
#include <adaptseg/vision/utility_rule.hpp>
#include <adaptseg/vision/visualization.hpp>
