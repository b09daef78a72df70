// The names of the experiment framework (namespace physgrad::run) that the reference experiments
// are written in, declared in namespace physgrad::experiments; only experiments/*.cpp include it.
#pragma once

#include "physgrad/run/cases/direct_runs.hpp"
#include "physgrad/run/cases/learning_case.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/cases/registry.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/run/cases/sampling.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"

namespace physgrad::experiments {

using run::DirectResult;
using run::Experiment;
using run::LearningCase;
using run::LearningExperiment;
using run::LearningResult;
using run::LearningSweep;
using run::OptionSpec;
using run::ReferenceCase;
using run::Registry;
using run::RuleDefaults;
using run::RuleSetup;
using run::RunContext;
using run::Sampler;
using run::Settings;

using run::format_value;
using run::held_controls;
using run::integer_option;
using run::iterations_cell;
using run::median;
using run::paired_seeds;
using run::ratio_text;
using run::real_list_option;
using run::real_option;
using run::require_start;
using run::sample_bytes;
using run::sample_count_option;
using run::sample_grid;
using run::text_list_option;
using run::text_option;
using run::value_text;
using run::verdict_sentence;

}  // namespace physgrad::experiments
