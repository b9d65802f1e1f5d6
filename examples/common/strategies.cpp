// run_strategy() instantiated once for every example program (the adaptseg_examples_common
// library): the planner and its policies are compiled here, for AnyBackend alone.

#include "strategies.hpp"

template adaptseg::StrategyRun adaptseg::run_strategy<adaptseg::AnyBackend>(
    const adaptseg::Field&, adaptseg::AnyBackend&, const std::string&, double, const adaptseg::DecisionModel*,
    adaptseg::MissionOptions, std::optional<double>, adaptseg::LawnmowerOverlap);
