// The front door physgrad/physgrad.hpp: this file includes nothing else of the library and uses
// parts of every layer; and the header lists every public header of the core library.
#include "physgrad/physgrad.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>

namespace {

namespace fs = std::filesystem;

TEST(FrontDoor, OneIncludeReachesDirectAndLearningRules) {
  physgrad::DiagonalScale physics(physgrad::Vector{{1.0, 100.0}});
  physgrad::L2Loss loss;
  physgrad::Objective objective(physics, loss, physgrad::Vector::Zero(2));
  const auto ig = physgrad::make_optimizer("ig");
  const physgrad::MinimizeSummary summary =
      physgrad::minimize(*ig, objective, physgrad::Vector{{0.5, 0.5}}, {.max_iterations = 3});
  EXPECT_LT(summary.loss, 1e-20);  // one full inverse-gradient step solves the linear toy
  const physgrad::Matrix j{{2.0, 0.0}, {0.0, 4.0}};
  EXPECT_TRUE(physgrad::power_pinv_apply(j, physgrad::Vector{{2.0, 4.0}})
                  .isApprox(physgrad::Vector{{1.0, 1.0}}));
  EXPECT_EQ(physgrad::make_learning_update("hig")->id(), "hig");
}

// The private headers, not installed: the lines of cmake/private_headers.txt but comments.
std::set<std::string> private_headers() {
  std::ifstream in(fs::path(PHYSGRAD_SOURCE_DIR) / "cmake" / "private_headers.txt");
  EXPECT_TRUE(in.good());
  std::set<std::string> headers;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') headers.insert("physgrad/" + line);
  }
  return headers;
}

// Every header under include/physgrad but report/ and run/ (libraries of their own), the private
// ones (among them the MPI communicator and the ScaLAPACK eigensolver, which need MPI) and the
// front door itself.
std::set<std::string> public_headers() {
  const fs::path root = fs::path(PHYSGRAD_SOURCE_DIR) / "include";
  const std::set<std::string> hidden = private_headers();
  std::set<std::string> headers;
  for (const auto& entry : fs::recursive_directory_iterator(root / "physgrad")) {
    if (!entry.is_regular_file() || entry.path().extension() != ".hpp") continue;
    const std::string name = fs::relative(entry.path(), root).generic_string();
    if (name.rfind("physgrad/report/", 0) == 0 || name.rfind("physgrad/run/", 0) == 0 ||
        hidden.contains(name) || name == "physgrad/physgrad.hpp") {
      continue;
    }
    headers.insert(name);
  }
  return headers;
}

TEST(FrontDoor, PrivateHeadersExist) {
  const std::set<std::string> hidden = private_headers();
  EXPECT_GT(hidden.size(), 10u);  // the list was read
  for (const std::string& header : hidden) {
    EXPECT_TRUE(fs::is_regular_file(fs::path(PHYSGRAD_SOURCE_DIR) / "include" / header))
        << "cmake/private_headers.txt names " << header << ", which does not exist";
  }
}

TEST(FrontDoor, IncludesEveryPublicHeaderOfTheLibrary) {
  std::ifstream in(fs::path(PHYSGRAD_SOURCE_DIR) / "include" / "physgrad" / "physgrad.hpp");
  ASSERT_TRUE(in.good());
  static const std::regex include(R"re(^\s*#\s*include\s*"([^"]+)")re");
  std::set<std::string> included;
  for (std::string line; std::getline(in, line);) {
    std::smatch match;
    if (std::regex_search(line, match, include)) included.insert(match[1]);
  }
  const std::set<std::string> expected = public_headers();
  EXPECT_GT(expected.size(), 50u);  // the tree was read
  for (const std::string& header : expected) {
    EXPECT_TRUE(included.contains(header)) << "physgrad.hpp does not include " << header;
  }
  for (const std::string& header : included) {
    EXPECT_TRUE(expected.contains(header)) << "physgrad.hpp includes " << header
                                           << ", which is not a public header of the library";
  }
}

}  // namespace
