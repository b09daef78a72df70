// The command-line tool as a test sees it: a fixture with its own working folder in which the
// `physgrad` binary runs, its exit code and output captured.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("physgrad_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
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

  Outcome run(const std::string& args) const {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string command = "cd '" + dir_.string() + "' && '" + PHYSGRAD_CLI + "' " + args +
                                " > '" + out.string() + "' 2> '" + err.string() + "'";
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
  // spawned.out / spawned.err beside the config files.
  pid_t spawn(const std::string& args) const {
    const std::string command = "cd '" + dir_.string() + "' && exec '" + PHYSGRAD_CLI + "' " +
                                args + " > '" + (configs_ / "spawned.out").string() + "' 2> '" +
                                (configs_ / "spawned.err").string() + "'";
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
