// The fixture of the tests that start the CLI under mpiexec on loopback: a test folder of its
// own, the launcher's command line (with what Open MPI needs as root and with more ranks than
// cores), and runs of the CLI that return the exit code and stderr.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace physgrad::testing {

class MpiFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("physgrad_mpi_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // "cd DIR && VARIABLES exec MPIEXEC ": the launcher, to be followed by its process counts and
  // programs. Open MPI refuses root (containers, CI) and more ranks than cores unless told. In a
  // sanitizer build LeakSanitizer ignores what Open MPI keeps until exit (full stacks, so that
  // the suppressions see its libraries). `env` adds variables (NAME=VALUE …).
  std::string launcher(const std::string& env = "") const {
    return "cd '" + dir_.string() +
           "' && OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
           "OMPI_MCA_rmaps_base_oversubscribe=1 LSAN_OPTIONS=suppressions=" +
           PHYSGRAD_LSAN_SUPPRESSIONS + ":fast_unwind_on_malloc=0 " + env + " exec " +
           PHYSGRAD_MPIEXEC + " ";
  }

  // The command line of `program` (default the CLI) with `args` in the test folder, under
  // mpiexec with `ranks` > 0.
  std::string command(int ranks, const std::string& args,
                      const std::string& program = PHYSGRAD_CLI) const {
    if (ranks == 0) return "cd '" + dir_.string() + "' && '" + program + "' " + args;
    return launcher() + PHYSGRAD_MPIEXEC_NUMPROC_FLAG + " " + std::to_string(ranks) + " '" +
           program + "' " + args;
  }

  // Runs `line` (a command() or launcher() line), stdout discarded; returns the exit code and
  // puts stderr into `err` when given.
  int run_line(const std::string& line, std::string* err = nullptr) const {
    const std::filesystem::path err_file = dir_.string() + "_stderr.txt";
    const std::string full = line + " > /dev/null 2> '" + err_file.string() + "'";
    const int status = std::system(full.c_str());
    if (err != nullptr) {
      std::ifstream in(err_file);
      std::stringstream text;
      text << in.rdbuf();
      *err = text.str();
    }
    std::filesystem::remove(err_file);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // Runs the CLI in the test folder, with `ranks` > 0 under mpiexec; returns the exit code.
  int run(int ranks, const std::string& args, std::string* err = nullptr,
          const std::string& program = PHYSGRAD_CLI) const {
    return run_line(command(ranks, args, program), err);
  }

  std::filesystem::path dir_;
};

}  // namespace physgrad::testing
