// The command-line tool as a test sees it: a fixture with its own working folder in which the
// `physgrad` binary runs, its exit code and output captured.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace physgrad::testing {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// Every file under `folder`: its path relative to `folder` → its content.
inline std::map<std::string, std::string> snapshot(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) {
      files[fs::relative(entry.path(), folder).string()] = read_file(entry.path());
    }
  }
  return files;
}

// A finished run folder: its summary and report, no checkpoint, nothing staged or temporary.
inline bool is_finished(const fs::path& folder) {
  if (!fs::exists(folder / "summary.json") || !fs::exists(folder / "report.html") ||
      fs::exists(folder / "checkpoint.pgc")) {
    return false;
  }
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().filename().string()[0] == '.') return false;
  }
  return true;
}

// A run folder's metrics.csv without its wall-clock column: what an interrupted and resumed run
// must reproduce exactly.
inline std::string metrics_without_time(const fs::path& folder) {
  // The fields of a CSV line; a quoted field may hold commas (a label such as "Adam (2-D, n=8)").
  const auto fields = [](const std::string& line) {
    std::vector<std::string> out(1);
    bool quoted = false;
    for (const char c : line) {
      if (c == '"') quoted = !quoted;
      if (c == ',' && !quoted) {
        out.emplace_back();
      } else {
        out.back() += c;
      }
    }
    return out;
  };
  std::istringstream lines(read_file(folder / "metrics.csv"));
  std::string header, result;
  std::getline(lines, header);
  const std::vector<std::string> names = fields(header);
  const auto skip = static_cast<std::size_t>(
      std::find(names.begin(), names.end(), "wall_seconds") - names.begin());
  EXPECT_LT(skip, names.size()) << header;
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> row = fields(line);
    if (skip < row.size()) row.erase(row.begin() + static_cast<std::ptrdiff_t>(skip));
    for (std::size_t i = 0; i < row.size(); ++i) result += (i ? "," : "") + row[i];
    result += "\n";
  }
  return result;
}

// Waits (up to two minutes) until `checkpoint` contains `needle`, sends `signal` to `pid` and
// returns its exit status.
inline int interrupt_when(pid_t pid, const fs::path& checkpoint, const std::string& needle,
                          int signal) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (read_file(checkpoint).find(needle) == std::string::npos &&
         std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, signal);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(test.begin(), test.end(), '/', '_');  // parameterised tests: "Name/param"
    dir_ = fs::temp_directory_path() / ("physgrad_cli_" + std::to_string(::getpid()) + "_" + test);
    configs_ = dir_.string() + "_configs";
    for (const fs::path& path : {dir_, configs_}) {
      fs::remove_all(path);
      fs::create_directories(path);
    }
  }
  void TearDown() override {
    fs::remove_all(dir_);
    fs::remove_all(configs_);
  }

  // A config file outside the run's working folder, so that folder stays empty on errors.
  std::string write_config(const std::string& name, const std::string& text) const {
    const fs::path path = configs_ / name;
    std::ofstream(path) << text;
    return path.string();
  }

  // Runs `physgrad ARGS` in the working folder (or its sub-folder `subdir`), with the
  // environment assignments `env` ("NAME=value …") in front, and waits for it.
  Outcome run(const std::string& args, const std::string& env = "",
              const std::string& subdir = "") const {
    const fs::path out = configs_ / "stdout.txt", err = configs_ / "stderr.txt";
    const std::string command = "cd '" + (dir_ / subdir).string() + "' && env " + env + " '" +
                                PHYSGRAD_CLI + "' " + args + " > '" + out.string() + "' 2> '" +
                                err.string() + "'";
    const int status = std::system(command.c_str());
    Outcome outcome;
    outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    outcome.out = read_file(out);
    outcome.err = read_file(err);
    fs::remove(out);
    fs::remove(err);
    return outcome;
  }

  // Starts `physgrad ARGS` in the working folder without waiting; its stdout and stderr go to
  // TAG.out / TAG.err beside the config files.
  pid_t spawn(const std::string& args, const std::string& env = "",
              const std::string& tag = "spawned") const {
    const std::string command = "cd '" + dir_.string() + "' && exec env " + env + " '" +
                                PHYSGRAD_CLI + "' " + args + " > '" +
                                (configs_ / (tag + ".out")).string() + "' 2> '" +
                                (configs_ / (tag + ".err")).string() + "'";
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    return pid;
  }

  // Exit 2, a single stderr line mentioning `needle`, and nothing left in the folder.
  void expect_rejected(const std::string& args, const std::string& needle) const {
    const Outcome outcome = run(args + " --out result");
    EXPECT_EQ(outcome.exit_code, 2) << args;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1)
        << args << ": " << outcome.err;
    EXPECT_NE(outcome.err.find(needle), std::string::npos) << args << ": " << outcome.err;
    EXPECT_TRUE(fs::is_empty(dir_)) << args << " left files behind";
  }

  fs::path dir_;
  fs::path configs_;
};

}  // namespace physgrad::testing
