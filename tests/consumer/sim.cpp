// adaptseg::sim from the installed package: the experiment layer's strategy table.
#include <adaptseg/sim/strategy.hpp>

#include <cstdio>

int main() {
  const adaptseg::StrategyInfo& lawnmower = adaptseg::strategy_info(adaptseg::kLawnmowerStrategy);
  const auto names = adaptseg::strategy_names(true);
  std::printf("sim consumer: %zu strategies fly a decision model, the lawnmower %s\n", names.size(),
              lawnmower.flies_model() ? "too" : "not");
  return !lawnmower.flies_model() && names.size() + 1 == adaptseg::kStrategyTable.size() ? 0 : 1;
}
