// physgrad — command-line front end: `physgrad list`, `physgrad describe NAME`,
// `physgrad run NAME [--config FILE.json] [options]`, `physgrad resume DIR`,
// `physgrad bench NAME [options]`, `physgrad report DIR`.
// Every error is one line on stderr and exit code 2; a run writes its folder only on success.
// SIGINT/SIGTERM stop a run: learning runs leave a checkpoint in the run folder (exit 128 +
// signal), other runs write nothing. Under mpirun the ranks first check that they were all
// started alike, and every exchange between them is bounded in time (ranks.hpp).
#include <CLI/CLI.hpp>
#include <cblas.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>
#include <new>
#include <optional>

#include "command_line.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/run/life/config_file.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/life/interrupt.hpp"
#include "registry.hpp"
#include "physgrad/run/run.hpp"
#include "physgrad/run/pages/run_index.hpp"
#include "physgrad/text.hpp"
#include "ranks.hpp"

namespace {

namespace ex = physgrad::run;
using physgrad::experiments::builtin_registry;
namespace fs = std::filesystem;

constexpr int kUsageError = 2;

// Every argument is a text value: refuse control characters (a NUL cuts a path short) and bytes
// that are not UTF-8 (config.json could not hold them), naming the option they belong to.
void check_arguments(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const std::string problem = physgrad::text_problem(argument);
    if (problem.empty()) continue;
    const std::size_t equals = argument.find('=');
    const std::string previous = i > 1 ? argv[i - 1] : "";
    if (argument.starts_with("--") && equals != std::string::npos) {  // --name=value
      const std::string value = argument.substr(equals + 1);
      const std::string value_problem = physgrad::text_problem(value);
      if (!value_problem.empty()) {
        throw physgrad::Error(argument.substr(0, equals) + ": " + physgrad::in_quotes(value) + " " +
                              value_problem);
      }
    }
    const std::string owner =
        previous.starts_with("--") ? previous : "argument " + std::to_string(i);
    throw physgrad::Error(owner + ": " + physgrad::in_quotes(argument) + " " + problem);
  }
}

// Throws Error "unknown subcommand 'NAME' (known: list, describe, …)" unless `name` is one
// (an empty name: "a subcommand is required (known: …)").
void check_subcommand(CLI::App& app, const std::string& name) {
  std::vector<std::string> known;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == name) return;
    known.push_back(sub->get_name());
  }
  if (name.empty()) {
    throw physgrad::Error("a subcommand is required (known: " + physgrad::comma_list(known) + ")");
  }
  throw physgrad::unknown_name_error("subcommand", name, known);
}

int usage_error(const std::string& message) {
  physgrad::cli::print_error(message);
  return physgrad::cli::end_run(kUsageError);  // under mpirun: ends the other ranks too
}

// OpenBLAS (Debian's build) takes a work buffer of 128 MiB per thread at its first level-3 call
// and retries for ever when it cannot have it. Check that an address-space limit (ulimit -v)
// leaves room for it, then take it now with one tiny dsyrk, before the run's own data: a later
// shortage is an ordinary allocation failure with a message. Without room the process ends at
// once: a BLAS thread may already be retrying, and exit() would wait for it.
void reserve_blas_buffer() {
  constexpr double kMiB = 1024.0 * 1024.0;
  try {
    physgrad::require_memory(160 * kMiB,
                             "the BLAS library's 128 MiB work buffer with 32 MiB to spare");
  } catch (const physgrad::Error& e) {
    physgrad::cli::print_error(e.what());
    std::_Exit(kUsageError);
  }
  const double one = 1;
  double product = 0;
  cblas_dsyrk(CblasColMajor, CblasLower, CblasNoTrans, 1, 1, 1.0, &one, 1, 0.0, &product, 1);
}

void print_table(const ex::RunContext::Table& table) {
  std::vector<std::size_t> widths(table.header.size(), 0);
  // Code points, not bytes, so α and ≤ line up.
  const auto width = [](const std::string& text) { return physgrad::code_points(text); };
  for (std::size_t c = 0; c < table.header.size(); ++c) widths[c] = width(table.header[c]);
  for (const auto& row : table.rows) {
    for (std::size_t c = 0; c < row.size() && c < widths.size(); ++c) {
      widths[c] = std::max(widths[c], width(row[c]));
    }
  }
  const auto print_row = [&](const std::vector<std::string>& row) {
    const std::size_t cells = std::min(row.size(), widths.size());
    for (std::size_t c = 0; c < cells; ++c) {
      std::cout << row[c];
      if (c + 1 < cells) std::cout << std::string(widths[c] - width(row[c]) + 2, ' ');
    }
    std::cout << '\n';
  };
  std::cout << table.title << '\n';
  print_row(table.header);
  for (const auto& row : table.rows) print_row(row);
  std::cout << '\n';
}

// The rule catalogue, one table per kind.
void print_rules(bool markdown) {
  using physgrad::RuleKind;
  for (const auto& [kind, title] :
       {std::pair{RuleKind::kDirect, "Direct optimization (Optimizer, minimize)"},
        std::pair{RuleKind::kLearning, "Learning (LearningUpdate, train_step, train)"}}) {
    if (markdown) {
      std::cout << physgrad::rule_table_markdown(kind) << '\n';
      continue;
    }
    ex::RunContext::Table table{title, {"id", "rule", "update", "options (defaults)"}, {}};
    for (const physgrad::RuleInfo& rule : physgrad::rule_catalogue()) {
      if (rule.kind != kind) continue;
      table.rows.push_back(
          {rule.id, rule.label, rule.formula, physgrad::rule_defaults_text(rule)});
    }
    print_table(table);
  }
}

// Progress on stderr: an updating line on a terminal, a plain line at most every 2 s otherwise.
class StderrProgress {
 public:
  void show(const std::string& line) {
    static const bool terminal = isatty(fileno(stderr)) != 0;
    const double now =
        std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    if (terminal) {
      std::cerr << "\r\033[K" << line << std::flush;
      line_open_ = true;
    } else if (now - last_seconds_ >= 2.0) {
      std::cerr << line << '\n';
      last_seconds_ = now;
    }
  }
  void end() {
    if (line_open_) std::cerr << '\n';
    line_open_ = false;
  }

 private:
  bool line_open_ = false;
  double last_seconds_ = -1e9;
};

// What the CLI gives a run: its progress and notices on stderr, the command line, the ranks.
ex::RunHooks cli_hooks(StderrProgress& progress, const std::string& command_line) {
  ex::RunHooks hooks;
  hooks.progress = [&progress](const std::string& line) { progress.show(line); };
  hooks.progress_end = [&progress] { progress.end(); };
  hooks.progress_event = [](const std::string& line) { std::cerr << line << '\n'; };
  hooks.log = [](const std::string& text) { std::cerr << "physgrad: " << text << '\n'; };
  hooks.command = command_line;
  hooks.communicator = physgrad::cli::communicator();
  return hooks;
}

// Prints what a run ended with; the exit code (128 + signal for a run stopped on request).
int report_outcome(const ex::RunOutcome& outcome) {
  if (!physgrad::cli::is_writer()) return outcome.finished ? 0 : 128 + outcome.signal;
  if (!outcome.finished) {
    std::cerr << "physgrad: " << outcome.stopped << '\n';
    return 128 + outcome.signal;
  }
  for (const auto& table : outcome.tables) print_table(table);
  std::cout << "report: " << outcome.report.string() << '\n';
  return 0;
}

// A new run of `experiment` with `settings`, resolved from the options `given`. A blank --out is
// refused (as Run::start refuses it) as it was typed, from `given`: the settings hold it without
// surrounding blanks.
int start_run(const ex::Experiment& experiment, const ex::Settings& settings,
              const ex::OptionTexts& given, const std::string& command_line) {
  fs::path out;
  if (settings.has("out") && settings.text("out").empty()) {
    for (const auto& [name, text] : given) {
      if (name == "out") out = text;  // the last one counts, as in the settings
    }
  }
  StderrProgress progress;
  return report_outcome(
      ex::Run::start(experiment, settings, out, cli_hooks(progress, command_line)));
}

// Parses the command line; a code to exit with when that ends the command (--help, a usage
// error). An unknown subcommand or experiment is named explicitly instead of CLI11's generic
// "A subcommand is required" or "not expected".
std::optional<int> parse_command_line(physgrad::cli::CommandLine& command, int argc, char** argv) {
  namespace cli = physgrad::cli;
  try {
    check_arguments(argc, argv);
    if (argc == 1 || argv[1][0] != '-') check_subcommand(command.app, argc > 1 ? argv[1] : "");
    if (argc > 2 && std::string(argv[1]) == "run" && argv[2][0] != '-') {
      builtin_registry().find(argv[2]);
    }
    command.app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help: the ranks compare it too, then print it
    const int code = cli::require_same_command(cli::rank_command(argc, argv, nullptr, nullptr));
    return code != 0 ? code : command.app.exit(e);
  } catch (const std::exception& e) {
    return usage_error(e.what());
  }
  return std::nullopt;
}

void print_experiments() {
  std::size_t width = 0;
  for (const auto& experiment : builtin_registry()) {
    width = std::max(width, experiment->name().size());
  }
  for (const auto& experiment : builtin_registry()) {
    std::cout << std::left << std::setw(static_cast<int>(width + 2)) << experiment->name()
              << experiment->description() << '\n';
  }
}

// Carries out the parsed subcommand: those that only print first, then the runs.
int carry_out(const physgrad::cli::CommandLine& command, const physgrad::cli::ChosenRun& chosen,
              const std::string& command_line) {
  if (command.list->parsed()) {
    print_experiments();
    return 0;
  }
  if (command.rules->parsed()) {
    print_rules(command.rules_markdown);
    return 0;
  }
  if (command.bench->parsed()) {
    reserve_blas_buffer();
    command.bench->run(std::cout);
    return 0;
  }
  if (command.report->parsed()) {
    const ex::RunIndex index = ex::write_run_index(builtin_registry(), command.report_folder);
    std::cout << "index of " << index.folders << " run folders: " << index.page.string() << '\n';
    return 0;
  }
  if (command.describe->parsed()) {
    print_table(ex::options_table(builtin_registry().find(command.describe_name)));
    return 0;
  }
  reserve_blas_buffer();
  ex::install_interrupt_handlers();
  if (command.resume->parsed()) {
    StderrProgress progress;
    return report_outcome(ex::Run::resume(builtin_registry(), command.resume_folder,
                                          cli_hooks(progress, command_line)));
  }
  if (chosen.experiment != nullptr) {
    return start_run(*chosen.experiment, *chosen.settings, chosen.given, command_line);
  }
  return 0;
}

// The command of this process: parses, checks that every rank was started alike, runs.
int run_command(int argc, char** argv) {
  namespace cli = physgrad::cli;
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
  cli::CommandLine command;
  if (const std::optional<int> code = parse_command_line(command, argc, argv)) return *code;
  try {
    // The run's experiment and settings first: the ranks compare them before anything is done.
    const cli::ChosenRun chosen = cli::chosen_run(command);
    const auto* settings = chosen.settings ? &*chosen.settings : nullptr;
    if (const int code =
            cli::require_same_command(cli::rank_command(argc, argv, chosen.experiment, settings));
        code != 0) {
      return code;
    }
    return carry_out(command, chosen, command_line);
  } catch (const std::bad_alloc&) {
    return usage_error("out of memory: a size given (samples, batch, grid, list) needs more than "
                       "this machine or its limits (ulimit -v) allow");
  } catch (const std::exception& e) {
    return usage_error(e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  const physgrad::cli::Ranks ranks(&argc, &argv);
  return physgrad::cli::finish(run_command(argc, argv));
}
