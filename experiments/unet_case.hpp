// The U-net of the grid experiments (heat-inverse, sip-poisson): phiml's u_net shape — levels,
// filters, batch norm, padding — as options, their checks and the sizes the learning checks need.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "physgrad/nn/conv_net.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "framework.hpp"

namespace physgrad::experiments {

// --levels, --filters, --batch-norm on|off, --padding zero|periodic (`padding` its default). The
// quick values keep the experiments' quick check small (4 filters; levels as given).
std::vector<run::OptionSpec> unet_option_specs(const std::string& padding);

// The U-net of `settings` for fields of n^dims cells, one channel in and one out.
UNetOptions unet_of(const run::Settings& settings, int dims, Index n);

// Throws Error when one sample's activations exceed the memory, unless n is a multiple of
// 2^(levels − 1) (each level halves the grid), and when batch norm is on while a selected rule (or the Adam→rule twin of --pretrain) needs per-sample
// Jacobians: batch norm normalises with the batch's own statistics, so one sample's output depends
// on the others and J of per-sample rows is not defined; those rules need --batch-norm off. With
// --batch given, also when twice such a rule's output cotangents (cells² doubles a sample) exceed
// the memory.
void check_unet(const run::Settings& settings, int dims, Index n);

// Throws Error when batch norm is on and the run's batches are shared among several processes
// (MPI): each rank would normalise its share with its own statistics, so the run would differ from
// the one-process run.
void check_unet_ranks(const run::Settings& settings, const run::RunContext& context);

// The sizes LearningExperiment's checks need for a U-net with `outputs` physics outputs per
// sample: |θ|, and |θ| multiply-adds per J Jᵀ entry (its gradient rows are formed).
run::LearningExperiment::Shape unet_shape(const UNetOptions& options, Index outputs);

// Bytes one sample of a U-net run needs at least: its `data_values` doubles and the activations
// kept for the backward pass (about 16 channels of every cell per filter and level, an estimate).
double unet_sample_bytes(const UNetOptions& options, Index data_values);

}  // namespace physgrad::experiments
