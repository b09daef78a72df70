// The layers of docs/architecture.md, read from the #include lines of every source file: a file
// includes only its own layer and the layers below it. In particular nothing below report/ draws
// (train/ and the library never include report/), and nothing below the experiment framework
// includes run/ or experiments/.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// The rank of each part, lowest first: a file may include its own rank and those below. The
// library's parts come first, then report/ (its own library, drawing only from core and io), the
// framework run/, the cases experiments/ and the command line.
const std::map<std::string, int>& ranks() {
  static const std::map<std::string, int> table = {
      {"core", 0},  // error, types, memory, threads, stop, text (top-level headers)
      {"io", 1},
      {"linalg", 2},
      {"physics", 3},    {"loss", 3},     {"nn", 3}, {"parallel", 3}, {"autodiff", 3},
      {"optim", 4},      {"inversion", 4},  // one layer: the numerical local inverse minimizes
      {"learn", 5},
      {"catalogue", 6},  {"rules", 6},
      {"train", 7},
      {"physgrad", 8},  // the front door physgrad.hpp: every part of the library
      {"report", 9},
      {"run", 10},
      {"experiments", 11},
      {"cli", 12},
  };
  return table;
}

// report/ is a library of its own on top of core and io only: neither the library's numerical
// parts nor train/ reach it, and it reaches none of them.
const std::vector<std::string> kReportMayInclude = {"core", "io", "report"};

// The part of a path below include/physgrad or src: its first folder, or for a top-level file
// "catalogue", "physgrad" or "core".
std::string part_of(const fs::path& relative) {
  const std::string first = relative.begin()->string();
  if (std::next(relative.begin()) != relative.end()) return first;  // in a folder
  const std::string stem = relative.stem().string();
  if (stem == "catalogue" || stem == "physgrad") return stem;
  return "core";
}

struct Include {
  std::string file;
  int line;
  std::string target;
};

std::vector<Include> includes_of(const fs::path& file, const fs::path& root) {
  static const std::regex quoted_include(R"re(^\s*#\s*include\s*"([^"]+)")re");
  std::vector<Include> found;
  std::ifstream in(file);
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    std::smatch match;
    if (std::regex_search(text, match, quoted_include)) {
      found.push_back({fs::relative(file, root).string(), line, match[1]});
    }
  }
  return found;
}

// The part an #include names: "physgrad/X/…" a library part, anything else a file next to the
// including one (its own part).
std::string included_part(const std::string& target, const std::string& own) {
  if (target.rfind("physgrad/", 0) != 0) return own;
  return part_of(fs::path(target.substr(9)));
}

// Whether a file of part `own` may include one of part `to`.
bool may_include(const std::string& own, const std::string& to) {
  if (own == "report") {
    return std::find(kReportMayInclude.begin(), kReportMayInclude.end(), to) !=
           kReportMayInclude.end();
  }
  if (to == "report") return ranks().at(own) > ranks().at("report");
  return ranks().at(to) <= ranks().at(own);
}

TEST(Layering, EveryIncludeStaysInItsLayerOrGoesDown) {
  const fs::path root = PHYSGRAD_SOURCE_DIR;
  // (folder, how its files' part is found)
  std::vector<std::pair<fs::path, std::optional<std::string>>> trees = {
      {root / "include" / "physgrad", std::nullopt},
      {root / "src", std::nullopt},
      {root / "experiments", "experiments"},
      {root / "apps", "cli"},
  };
  std::size_t checked = 0;
  for (const auto& [tree, fixed] : trees) {
    ASSERT_TRUE(fs::is_directory(tree)) << tree;
    for (const auto& entry : fs::recursive_directory_iterator(tree)) {
      const std::string extension = entry.path().extension().string();
      if (!entry.is_regular_file() || (extension != ".hpp" && extension != ".cpp")) continue;
      const std::string own = fixed ? *fixed : part_of(fs::relative(entry.path(), tree));
      ASSERT_TRUE(ranks().contains(own))
          << entry.path() << " is in a part the layering does not know (" << own
          << "): give it its place in this test and in docs/architecture.md";
      for (const Include& include : includes_of(entry.path(), root)) {
        const std::string to = included_part(include.target, own);
        ASSERT_TRUE(ranks().contains(to)) << include.file << ":" << include.line << " includes "
                                          << include.target << ", a part the layering does not know";
        EXPECT_TRUE(may_include(own, to)) << include.file << ":" << include.line << ": " << own
                             << " includes " << include.target << " (" << to << "), above it";
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 300u);  // the trees were read
}

TEST(Layering, TheCheckRefusesWhatGoesUp) {
  EXPECT_EQ(part_of("train/trainer.hpp"), "train");
  EXPECT_EQ(part_of("catalogue.hpp"), "catalogue");
  EXPECT_EQ(part_of("error.hpp"), "core");
  EXPECT_EQ(included_part("physgrad/report/line_plot.hpp", "train"), "report");
  EXPECT_EQ(included_part("checkpoint.hpp", "experiments"), "experiments");
  for (const auto& [own, to] : std::vector<std::pair<std::string, std::string>>{
           {"train", "report"}, {"learn", "report"}, {"physgrad", "report"}, {"report", "train"},
           {"report", "physics"}, {"train", "run"}, {"report", "run"}, {"run", "experiments"},
           {"optim", "learn"}, {"io", "linalg"}, {"core", "io"}, {"experiments", "cli"}}) {
    EXPECT_FALSE(may_include(own, to)) << own << " → " << to;
  }
  for (const auto& [own, to] : std::vector<std::pair<std::string, std::string>>{
           {"report", "io"}, {"report", "core"}, {"run", "report"}, {"run", "train"},
           {"experiments", "run"}, {"cli", "run"}, {"train", "learn"}, {"learn", "optim"},
           {"physics", "physics"}, {"nn", "core"}}) {
    EXPECT_TRUE(may_include(own, to)) << own << " → " << to;
  }
}

}  // namespace
