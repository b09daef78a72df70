// CommandLine — the subcommands of the physgrad command and the values they read: list, describe,
// run (each experiment a subcommand whose options are read as text), resume, rules, bench, report.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bench_command.hpp"
#include "physgrad/run/life/config_file.hpp"
#include "physgrad/run/life/experiment.hpp"

namespace physgrad::cli {

// Made once by the command; the values are bound to its options, so it stays where it was made.
struct CommandLine {
  CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  CLI::App app{"physgrad — inversion-based optimization for physics-based deep learning"};
  CLI::App* list = nullptr;
  CLI::App* describe = nullptr;
  CLI::App* run = nullptr;
  CLI::App* resume = nullptr;
  CLI::App* rules = nullptr;
  CLI::App* report = nullptr;
  std::optional<BenchCommand> bench;
  std::string describe_name, resume_folder, report_folder;
  bool rules_markdown = false;

  // Per experiment (by name): its option texts, its options, its --config file and option.
  std::map<std::string, std::map<std::string, std::string>> texts;
  std::map<std::string, std::vector<CLI::Option*>> options;
  std::map<std::string, std::string> config_files;
  std::map<std::string, CLI::Option*> config_file_options;
};

// The experiment `run` was given (none for another subcommand), the option texts given to it
// (the --config file's first, so that flags given on the command line override them) and the
// settings they resolve to.
struct ChosenRun {
  const run::Experiment* experiment = nullptr;
  run::OptionTexts given;
  std::optional<run::Settings> settings;
};
ChosenRun chosen_run(CommandLine& command);

}  // namespace physgrad::cli
