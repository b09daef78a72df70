// Test helper: runs a registered experiment through the experiment API (settings resolved as
// the CLI does, progress silenced) and returns what it collected.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "registry.hpp"
#include "physgrad/run/life/experiment.hpp"

namespace physgrad::run::testing {

inline RunContext run_experiment(const std::string& name,
                                 const std::vector<std::pair<std::string, std::string>>& given) {
  const Experiment& experiment = experiments::builtin_registry().find(name);
  RunContext context;
  experiment.run(resolve_settings(experiment, given), context);
  return context;
}

}  // namespace physgrad::run::testing
