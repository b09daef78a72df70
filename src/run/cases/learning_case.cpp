#include "physgrad/run/cases/learning_case.hpp"

#include "physgrad/run/cases/learning_experiment.hpp"

namespace physgrad::run {

Dataset LearningCase::training_set(Index count, std::uint64_t seed) const {
  return samples(2 * seed, count);
}

Dataset LearningCase::test_set(Index count, std::uint64_t seed) const {
  return samples(2 * seed + 1, count);
}

ReferenceCase LearningCase::reference(Index batch, std::uint64_t seed) const {
  return ReferenceCase{physics, loss, network(seed), training_set(batch, seed), defaults};
}

}  // namespace physgrad::run
