#pragma once
/// @file
/// Umbrella header of the core (CMake target adaptseg::adaptseg; Eigen and LBFGSpp only): the
/// camera and flight-time models, the lawnmower planner and inspection tours, the Gaussian process,
/// the decision inputs, the gain models and the decision rules (docs/method.md).

#include <adaptseg/core/area.hpp>
#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/camera_presets.hpp>
#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/cell_input_scores.hpp>
#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/field_estimates.hpp>
#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/core/front_aware_settings.hpp>
#include <adaptseg/core/gain_model.hpp>
#include <adaptseg/core/gaussian_process.hpp>
#include <adaptseg/core/gp_kernel.hpp>
#include <adaptseg/core/gp_options.hpp>
#include <adaptseg/core/inspection_tour.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/core/map_fusion.hpp>
#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/core/time_account.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/core/top_level.hpp>
#include <adaptseg/core/utility_policy.hpp>
#include <adaptseg/core/version.hpp>
