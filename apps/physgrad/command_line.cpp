#include "command_line.hpp"

#include "registry.hpp"

namespace physgrad::cli {

namespace {

std::string type_name(const run::OptionSpec& spec) {
  switch (spec.kind) {
    case run::OptionSpec::Kind::kReal: return "NUMBER";
    case run::OptionSpec::Kind::kInteger: return "INT";
    case run::OptionSpec::Kind::kText: return "TEXT";
    case run::OptionSpec::Kind::kRealList: return "NUMBERS";
    case run::OptionSpec::Kind::kTextList: return "NAMES";
  }
  return "TEXT";
}

std::string option_help(const run::OptionSpec& spec) {
  std::string help = spec.help;
  const std::string range = run::describe_range(spec);
  if (!range.empty()) help += " (" + range + ")";
  return help;
}

// Each experiment is a subcommand of `run` with its own options, all read as text and validated
// by the experiment framework so every bad value gets the same kind of message.
void add_experiment_commands(CommandLine& command) {
  for (const auto& experiment : experiments::builtin_registry()) {
    const std::string& name = experiment->name();
    CLI::App* sub = command.run->add_subcommand(name, experiment->description());
    command.config_file_options[name] =
        sub->add_option("--config", command.config_files[name],
                        "read option values from a JSON file (keys: option names; flags win)")
            ->type_name("FILE.json");
    for (const run::OptionSpec& spec : run::all_options(*experiment)) {
      CLI::Option* option =
          sub->add_option("--" + spec.name, command.texts[name][spec.name], option_help(spec));
      option->default_str(spec.default_text)->type_name(type_name(spec));
      command.options[name].push_back(option);
    }
  }
}

}  // namespace

CommandLine::CommandLine() {
  app.require_subcommand(1);
  list = app.add_subcommand("list", "list the experiments");
  describe = app.add_subcommand("describe", "show an experiment's options: kind, default, range");
  describe->add_option("NAME", describe_name, "experiment name (see list)")->required();
  run = app.add_subcommand("run",
                           "run an experiment: physgrad run NAME [--config FILE.json] [options]");
  run->require_subcommand(1);
  resume = app.add_subcommand("resume",
                              "continue an interrupted run from the checkpoint in its folder");
  resume->add_option("DIR", resume_folder, "the run folder (its --out)")->required();
  rules = app.add_subcommand("rules", "the update rules: id, update, options and their defaults");
  rules->add_flag("--markdown", rules_markdown, "as the Markdown tables of docs/update_rules.md");
  bench.emplace(app);
  report = app.add_subcommand(
      "report", "write DIR/index.html over the run folders in DIR: every run's results and the "
                "loss curves of all runs overlaid");
  report->add_option("DIR", report_folder, "a folder of run folders, e.g. runs")->required();
  add_experiment_commands(*this);
}

ChosenRun chosen_run(CommandLine& command) {
  ChosenRun chosen;
  for (const auto& candidate : experiments::builtin_registry()) {
    if (!command.run->get_subcommand(candidate->name())->parsed()) continue;
    chosen.experiment = candidate.get();
    const std::string& name = candidate->name();
    if (command.config_file_options[name]->count() > 0) {
      chosen.given = run::read_config_file(*candidate, command.config_files[name]);
    }
    for (CLI::Option* option : command.options[name]) {
      if (option->count() == 0) continue;
      const std::string option_name = option->get_name().substr(2);  // drop "--"
      chosen.given.emplace_back(option_name, command.texts[name][option_name]);
    }
    chosen.settings.emplace(run::resolve_settings(*candidate, chosen.given));
  }
  return chosen;
}

}  // namespace physgrad::cli
