// heat-inverse's reconstruction figures: for a few test samples the true initial state x*, the
// diffused y* = P(x*) and every rule's reconstruction f(y*), as steps over cells (1-D) or fields.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/nn/network.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "framework.hpp"

namespace physgrad::experiments {

// A rule's run and the network it trained.
using TrainedNetworks = std::vector<std::pair<const run::LearningResult*, std::shared_ptr<Network>>>;

// Per shown test sample (the first `count`): x*, y* and every rule's x as steps over the cells
// [i, i + 1) of a line.
void add_line_reconstructions(run::RunContext& context, const Matrix& truth, const Matrix& inputs,
                              const TrainedNetworks& trained, Index count);

// Per shown test sample one row of n×n panels in one colour range: x*, y* and every rule's x;
// `input` says what y* is ("diffused"), `value` what the fields hold ("temperature").
struct FieldWords {
  std::string input;
  std::string value;
};
void add_field_reconstructions(run::RunContext& context, Index n, const Matrix& truth,
                               const Matrix& inputs, const TrainedNetworks& trained, Index count,
                               const FieldWords& words);

}  // namespace physgrad::experiments
