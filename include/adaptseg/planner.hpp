#pragma once
/// @file
/// Umbrella header: every component. Backends that need heavy integrations (the ERFNet
/// backend through OpenCV DNN) stay out of it, behind their own header and CMake component.

#include <adaptseg/camera.hpp>
#include <adaptseg/error.hpp>
#include <adaptseg/field.hpp>
#include <adaptseg/lawnmower_planner.hpp>
#include <adaptseg/metrics.hpp>
#include <adaptseg/mission.hpp>
#include <adaptseg/oracle_segmenter.hpp>
#include <adaptseg/segmentation_backend.hpp>
#include <adaptseg/semantic_map.hpp>
#include <adaptseg/simulated_sensor.hpp>
#include <adaptseg/timing.hpp>
#include <adaptseg/version.hpp>
#include <adaptseg/visualization.hpp>
