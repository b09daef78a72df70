// The command-line tool end to end: bad input gives one line on stderr naming the bad value,
// exit code 2 and no output; a good run writes the whole run folder.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string read_file(const fs::path& path) {
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
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

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
};

TEST_F(Cli, BadInputIsOneLineExitTwoAndWritesNothing) {
  expect_rejected("run no-such-experiment", "'no-such-experiment'");
  expect_rejected("run scaled-toy --optimizers gd,sgdd", "'sgdd'");
  expect_rejected("run scaled-toy --lr -0.5", "-0.5");
  expect_rejected("run scaled-toy --lr 0", "'0'");
  expect_rejected("run scaled-toy --lr nan", "nan");
  expect_rejected("run scaled-toy --lr fast", "'fast'");
  expect_rejected("run scaled-toy --iters 0", "'0'");
  expect_rejected("run scaled-toy --iters 2.5", "'2.5'");
  expect_rejected("run scaled-toy --alpha 1,0", "'0'");
  expect_rejected("run scaled-toy --start 1,2,3", "got 3");
  expect_rejected("run scaled-toy --start 0,0", "(0, 0)");
  expect_rejected("run comparison --pg-inverse magic", "'magic'");
  expect_rejected("run sensitivity --no-such-option 1", "--no-such-option");
}

TEST_F(Cli, UnwritableOutputFolderIsRejected) {
  {
    std::ofstream file(dir_ / "a-file");
  }
  for (const std::string out : {"a-file/sub", "/proc/physgrad-run"}) {
    const Outcome outcome = run("run scaled-toy --iters 5 --out " + out);
    EXPECT_EQ(outcome.exit_code, 2) << out;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1) << outcome.err;
    EXPECT_NE(outcome.err.find(out.substr(0, out.find('/', 1))), std::string::npos)
        << outcome.err;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
  // A non-empty folder is never overwritten.
  fs::create_directories(dir_ / "full");
  { std::ofstream keep(dir_ / "full" / "keep.txt"); }
  const Outcome outcome = run("run scaled-toy --iters 5 --out full");
  EXPECT_EQ(outcome.exit_code, 2);
  EXPECT_NE(outcome.err.find("not empty"), std::string::npos) << outcome.err;
  EXPECT_TRUE(fs::exists(dir_ / "full" / "keep.txt"));
}

TEST_F(Cli, HelpListsEveryOptionWithItsDefault) {
  const Outcome top = run("--help");
  EXPECT_EQ(top.exit_code, 0);
  EXPECT_NE(top.out.find("run"), std::string::npos);
  const Outcome help = run("run scaled-toy --help");
  EXPECT_EQ(help.exit_code, 0);
  for (const std::string option : {"--optimizers", "--iters", "--lr", "--seed", "--out",
                                   "--alpha", "--start", "--tol", "--tol-mode"}) {
    EXPECT_NE(help.out.find(option), std::string::npos) << option;
  }
  EXPECT_NE(help.out.find("1,10,100,1000"), std::string::npos) << help.out;
  const Outcome list = run("list");
  EXPECT_EQ(list.exit_code, 0);
  for (const std::string name : {"scaled-toy", "sensitivity", "comparison"}) {
    EXPECT_NE(list.out.find(name), std::string::npos) << name;
  }
}

TEST_F(Cli, RunWritesTheWholeRunFolder) {
  const Outcome outcome = run("run comparison --out result");
  ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
  const fs::path result = dir_ / "result";
  for (const std::string file : {"config.json", "metrics.csv", "summary.json", "report.html",
                                 "trajectories_x.svg", "trajectories_y.svg", "loss.svg"}) {
    EXPECT_TRUE(fs::exists(result / file)) << file;
  }
  const auto summary = nlohmann::json::parse(read_file(result / "summary.json"));
  EXPECT_EQ(summary["experiment"], "comparison");
  // gd, adam, newton, ig and PG with two inverses.
  ASSERT_EQ(summary["runs"].size(), 6u);
  for (const auto& entry : summary["runs"]) {
    for (const char* key : {"label", "optimizer", "params", "initial", "final", "iterations",
                            "wall_seconds"}) {
      EXPECT_TRUE(entry.contains(key)) << key;
    }
    EXPECT_LT(entry["final"]["loss"].get<double>(), entry["initial"]["loss"].get<double>())
        << entry["label"];
  }
  const auto config = nlohmann::json::parse(read_file(result / "config.json"));
  EXPECT_EQ(config["settings"]["iters"], 10);
  // Staging folders never stay behind.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".result.partial"), std::string::npos);
  }
}

}  // namespace
