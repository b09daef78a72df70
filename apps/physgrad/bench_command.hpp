// `physgrad bench NAME [--optimizer U] [--batch B] [--steps N] [--warmup W] [--threads T]`:
// times N steps of update U on reference experiment NAME after W warm-up steps and prints one
// JSON line.
#pragma once

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

namespace physgrad::cli {

class BenchCommand {
 public:
  // Adds the subcommand to `app`; every value is read as text and checked by run().
  explicit BenchCommand(CLI::App& app);
  bool parsed() const { return command_->parsed(); }
  // Runs the timing and writes the JSON line to `out`. Throws Error on a bad name or value.
  void run(std::ostream& out) const;

 private:
  CLI::App* command_;
  std::string name_;
  std::string optimizer_ = "hig";
  std::string batch_;
  std::string steps_ = "10";
  std::string warmup_ = "2";
  std::string threads_ = "1";
};

}  // namespace physgrad::cli
