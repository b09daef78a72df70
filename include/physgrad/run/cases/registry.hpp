// Registry — the experiments a front end offers, in display order and found by name, and the
// reference cases of the learning experiments among them (what `physgrad bench` and the
// micro-benchmarks time). The front end builds it and hands it to Run::resume and the index: the
// CLI the built-in experiments (experiments/registry.hpp), a program its own, with them or not.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"

namespace physgrad::run {

class Registry {
 public:
  // Throws Error when two experiments have one name.
  explicit Registry(std::vector<std::unique_ptr<Experiment>> experiments);

  const std::vector<std::unique_ptr<Experiment>>& experiments() const { return experiments_; }
  auto begin() const { return experiments_.begin(); }
  auto end() const { return experiments_.end(); }

  // Throws Error "unknown experiment 'NAME' (known: …)".
  const Experiment& find(const std::string& name) const;

  // The learning experiments with a reference case, in display order.
  std::vector<std::string> reference_names() const;
  // NAME's reference case with a batch of `batch` samples; seed as --seed of `physgrad run`.
  // Throws Error for batch < 1 or a NAME without one ("unknown reference configuration 'NAME'
  // (known: …)").
  ReferenceCase reference(const std::string& name, Index batch, std::uint64_t seed = 0) const;

 private:
  std::vector<std::unique_ptr<Experiment>> experiments_;
};

}  // namespace physgrad::run
