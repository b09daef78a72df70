// The layers of docs/architecture.md, read from the #include lines of every source file: a file
// includes only its own layer and the layers below it. In particular nothing below report/ draws
// (train/ and the library never include report/), and nothing below the experiment framework
// includes run/ or experiments/; inversion/ lies below optim/, which holds the local inverses.
#include <gtest/gtest.h>
#include <unistd.h>

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
// framework run/, the cases experiments/ and the command line. inversion/ (J^{−κ}g, Δy) lies
// below optim/: the local inverses that minimize with the direct rules live in optim/.
const std::map<std::string, int>& ranks() {
  static const std::map<std::string, int> table = {
      {"core", 0},  // error, types, memory, threads, stop, text (top-level headers)
      {"io", 1},
      {"physics", 2},    {"loss", 2},     {"nn", 2}, {"parallel", 2}, {"autodiff", 2},
      {"inversion", 3},
      {"optim", 4},
      {"learn", 5},
      {"catalogue", 6},
      {"train", 7},
      {"physgrad", 8},  // the front door physgrad.hpp: every part of the library
      {"report", 9},
      {"run/life", 10},   // run/: the run's life (settings, folder, checkpoint, interrupt),
      {"run/cases", 11},  // the learning cases and sweeps, the verdicts and pages,
      {"run/pages", 12},
      {"run", 13},        // and on top run.hpp, the run from claim to commit
      {"experiments", 14},
      {"cli", 15},
  };
  return table;
}

// report/ is a library of its own on top of core and io only: neither the library's numerical
// parts nor train/ reach it, and it reaches none of them.
const std::vector<std::string> kReportMayInclude = {"core", "io", "report"};

// The part of a path below include/physgrad or src: its first folder (in run/ its first two,
// "run/life"), or for a top-level file "catalogue", "physgrad" or "core".
std::string part_of(const fs::path& relative) {
  const std::string first = relative.begin()->string();
  const auto second = std::next(relative.begin());
  if (first == "run" && second != relative.end() && std::next(second) != relative.end()) {
    return first + "/" + second->string();  // a room of run/
  }
  if (second != relative.end()) return first;  // in a folder
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

// Every include of the source tree at `root` (include/physgrad, src, experiments, apps) that
// goes up, or names or sits in a part the layering does not know, as "FILE:LINE: …"; `checked`
// counts the includes read.
std::vector<std::string> layering_problems(const fs::path& root, std::size_t& checked) {
  // (folder, how its files' part is found)
  const std::vector<std::pair<fs::path, std::optional<std::string>>> trees = {
      {root / "include" / "physgrad", std::nullopt},
      {root / "src", std::nullopt},
      {root / "experiments", "experiments"},
      {root / "apps", "cli"},
  };
  std::vector<std::string> problems;
  checked = 0;
  for (const auto& [tree, fixed] : trees) {
    if (!fs::is_directory(tree)) {
      problems.push_back(tree.string() + " is not a folder");
      continue;
    }
    for (const auto& entry : fs::recursive_directory_iterator(tree)) {
      const std::string extension = entry.path().extension().string();
      if (!entry.is_regular_file() || (extension != ".hpp" && extension != ".cpp")) continue;
      const std::string own = fixed ? *fixed : part_of(fs::relative(entry.path(), tree));
      if (!ranks().contains(own)) {
        problems.push_back(fs::relative(entry.path(), root).string() +
                           " is in a part the layering does not know (" + own +
                           "): give it its place in this test and in docs/architecture.md");
        continue;
      }
      for (const Include& include : includes_of(entry.path(), root)) {
        const std::string to = included_part(include.target, own);
        const std::string where = include.file + ":" + std::to_string(include.line) + ": ";
        if (!ranks().contains(to)) {
          problems.push_back(where + "includes " + include.target +
                             ", a part the layering does not know");
        } else if (!may_include(own, to)) {
          problems.push_back(where + own + " includes " + include.target + " (" + to +
                             "), above it");
        }
        ++checked;
      }
    }
  }
  return problems;
}

TEST(Layering, EveryIncludeStaysInItsLayerOrGoesDown) {
  std::size_t checked = 0;
  for (const std::string& problem : layering_problems(PHYSGRAD_SOURCE_DIR, checked)) {
    ADD_FAILURE() << problem;
  }
  EXPECT_GT(checked, 300u);  // the trees were read
}

// The check itself on a made-up tree: an include from inversion/ up to optim/ and a folder the
// layering does not know are found, the includes that go down are not.
TEST(Layering, TheCheckFindsAnIncludeFromInversionUpToOptim) {
  const fs::path root = fs::temp_directory_path() /
                        ("physgrad_layering_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const auto write = [&root](const fs::path& file, const std::string& text) {
    fs::create_directories((root / file).parent_path());
    std::ofstream(root / file) << text;
  };
  write("include/physgrad/inversion/step.hpp",
        "#pragma once\n#include \"physgrad/types.hpp\"\n#include \"physgrad/optim/minimize.hpp\"\n");
  write("src/inversion/step.cpp", "#include \"physgrad/inversion/step.hpp\"\n");
  write("src/optim/rule.cpp", "#include \"physgrad/inversion/power_pinv.hpp\"\n");
  write("src/linalg/old.cpp", "#include \"physgrad/types.hpp\"\n");
  write("experiments/case.cpp", "#include \"physgrad/run/run.hpp\"\n");
  write("apps/physgrad/main.cpp", "#include \"physgrad/run/run.hpp\"\n");
  std::size_t checked = 0;
  const std::vector<std::string> problems = layering_problems(root, checked);
  fs::remove_all(root);
  EXPECT_EQ(checked, 6u);
  ASSERT_EQ(problems.size(), 2u) << ::testing::PrintToString(problems);
  const auto found = [&problems](const std::string& text) {
    return std::any_of(problems.begin(), problems.end(), [&text](const std::string& p) {
      return p.find(text) != std::string::npos;
    });
  };
  EXPECT_TRUE(found("include/physgrad/inversion/step.hpp:3: inversion includes "
                    "physgrad/optim/minimize.hpp (optim), above it"))
      << ::testing::PrintToString(problems);
  EXPECT_TRUE(found("src/linalg/old.cpp is in a part the layering does not know (linalg)"))
      << ::testing::PrintToString(problems);
}

TEST(Layering, TheCheckRefusesWhatGoesUp) {
  EXPECT_EQ(part_of("train/trainer.hpp"), "train");
  EXPECT_EQ(part_of("catalogue.hpp"), "catalogue");
  EXPECT_EQ(part_of("error.hpp"), "core");
  EXPECT_EQ(part_of("run/run.hpp"), "run");
  EXPECT_EQ(part_of("run/pages/run_index.hpp"), "run/pages");
  EXPECT_EQ(included_part("physgrad/report/line_plot.hpp", "train"), "report");
  EXPECT_EQ(included_part("checkpoint.hpp", "experiments"), "experiments");
  for (const auto& [own, to] : std::vector<std::pair<std::string, std::string>>{
           {"train", "report"}, {"learn", "report"}, {"physgrad", "report"}, {"report", "train"},
           {"report", "physics"}, {"train", "run"}, {"report", "run"}, {"run", "experiments"},
           {"optim", "learn"}, {"io", "physics"}, {"core", "io"}, {"experiments", "cli"},
           {"inversion", "optim"}, {"inversion", "learn"}, {"physics", "inversion"},
           {"run/life", "run/cases"}, {"run/cases", "run/pages"}, {"run/pages", "run"},
           {"run/life", "run"}}) {
    EXPECT_FALSE(may_include(own, to)) << own << " → " << to;
  }
  for (const auto& [own, to] : std::vector<std::pair<std::string, std::string>>{
           {"report", "io"}, {"report", "core"}, {"run", "report"}, {"run", "train"},
           {"experiments", "run"}, {"cli", "run"}, {"train", "learn"}, {"learn", "optim"},
           {"physics", "physics"}, {"nn", "core"}, {"optim", "inversion"},
           {"learn", "inversion"}, {"run/pages", "run/cases"}, {"run/cases", "run/life"},
           {"run", "run/pages"}, {"experiments", "run/cases"}, {"run/life", "report"}}) {
    EXPECT_TRUE(may_include(own, to)) << own << " → " << to;
  }
}

}  // namespace
