// The layers of docs/architecture.md at link time, read from the target_link_libraries calls of
// the top-level CMakeLists.txt: a library links only the libraries below it. In particular the
// experiment framework (physgrad_run) links no experiment: Run::resume and the index take their
// Registry from the caller, so a program links physgrad_run with experiments of its own.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// The rank of each library target, lowest first: a target links only those of lower rank.
// report/ and the MPI communicator sit beside each other on the library; the framework run/ on
// report/; the reference experiments on run/; the command line on all of them.
const std::map<std::string, int>& link_ranks() {
  static const std::map<std::string, int> table = {
      {"physgrad", 0},
      {"physgrad_report", 1}, {"physgrad_mpi", 1},
      {"physgrad_run", 2},
      {"physgrad_experiments", 3},
      {"physgrad_cli", 4},
  };
  return table;
}

// A library name as the table has it: physgrad::run is physgrad_run, physgrad::physgrad physgrad.
std::string link_target_name(const std::string& name) {
  if (name.rfind("physgrad::", 0) != 0) return name;
  const std::string rest = name.substr(10);
  return rest == "physgrad" ? rest : "physgrad_" + rest;
}

// The text of a CMake file without its comments (from # to the end of the line, outside quotes).
std::string without_cmake_comments(std::istream& in) {
  std::string out, line;
  while (std::getline(in, line)) {
    bool quoted = false;
    for (const char c : line) {
      if (c == '"') quoted = !quoted;
      if (c == '#' && !quoted) break;
      out += c;
    }
    out += '\n';
  }
  return out;
}

// Every physgrad library one of the ranked targets links, in `cmake_file`, that is not below it
// (or that the table does not know), as "TARGET links NAME, …"; `checked` counts the links read.
std::vector<std::string> link_problems(const fs::path& cmake_file, std::size_t& checked) {
  std::ifstream in(cmake_file);
  if (!in) return {cmake_file.string() + " cannot be read"};
  const std::string text = without_cmake_comments(in);
  static const std::regex call(R"re(target_link_libraries\s*\(([^)]*)\))re");
  static const std::regex word(R"re([A-Za-z0-9_:]+)re");
  std::vector<std::string> problems;
  checked = 0;
  for (auto m = std::sregex_iterator(text.begin(), text.end(), call); m != std::sregex_iterator();
       ++m) {
    const std::string arguments = (*m)[1];
    std::vector<std::string> words;
    for (auto w = std::sregex_iterator(arguments.begin(), arguments.end(), word);
         w != std::sregex_iterator(); ++w) {
      words.push_back(w->str());
    }
    if (words.empty() || !link_ranks().contains(words.front())) continue;
    const std::string& target = words.front();
    for (std::size_t i = 1; i < words.size(); ++i) {
      const std::string linked = link_target_name(words[i]);
      if (linked != "physgrad" && linked.rfind("physgrad_", 0) != 0) continue;  // not ours
      ++checked;
      if (!link_ranks().contains(linked)) {
        problems.push_back(target + " links " + words[i] +
                           ", a library the link layering does not know");
      } else if (link_ranks().at(linked) >= link_ranks().at(target)) {
        problems.push_back(target + " links " + words[i] + ", which is not below it");
      }
    }
  }
  return problems;
}

TEST(LinkLayering, EveryLibraryLinksOnlyTheLibrariesBelowIt) {
  std::size_t checked = 0;
  const fs::path cmake_file = fs::path(PHYSGRAD_SOURCE_DIR) / "CMakeLists.txt";
  for (const std::string& problem : link_problems(cmake_file, checked)) {
    ADD_FAILURE() << problem;
  }
  EXPECT_GE(checked, 5u);  // report, run, experiments and the command line link physgrad's own
}

// The check itself on a made-up CMakeLists.txt: run/ linking the experiments (as an INTERFACE
// dependency over two lines, or by its alias) and a library the table does not know are found;
// the links that go down, and those in comments, are not.
TEST(LinkLayering, TheCheckFindsALinkFromRunUpToTheExperiments) {
  const fs::path file = fs::temp_directory_path() /
                        ("physgrad_link_layering_" + std::to_string(::getpid()) + ".txt");
  std::ofstream(file)
      << "add_library(physgrad_run STATIC ${SOURCES})\n"
         "target_link_libraries(physgrad_run PUBLIC physgrad_report)\n"
         "target_link_libraries(physgrad_experiments PUBLIC physgrad::run)\n"
         "# target_link_libraries(physgrad_run PUBLIC physgrad_cli)\n"
         "target_link_libraries(physgrad_run\n  INTERFACE physgrad_experiments)\n"
         "target_link_libraries(physgrad_report PRIVATE physgrad::physgrad physgrad::run)\n"
         "target_link_libraries(physgrad_cli PRIVATE physgrad_extras CLI11::CLI11)\n"
         "target_link_libraries(some_test PRIVATE physgrad_cli)\n";
  std::size_t checked = 0;
  const std::vector<std::string> problems = link_problems(file, checked);
  fs::remove(file);
  EXPECT_EQ(checked, 6u);
  EXPECT_EQ(problems, (std::vector<std::string>{
                          "physgrad_run links physgrad_experiments, which is not below it",
                          "physgrad_report links physgrad::run, which is not below it",
                          "physgrad_cli links physgrad_extras, a library the link layering does "
                          "not know"}));
}

TEST(LinkLayering, AliasesNameTheirLibrary) {
  EXPECT_EQ(link_target_name("physgrad::physgrad"), "physgrad");
  EXPECT_EQ(link_target_name("physgrad::run"), "physgrad_run");
  EXPECT_EQ(link_target_name("physgrad_run"), "physgrad_run");
  EXPECT_EQ(link_target_name("CLI11::CLI11"), "CLI11::CLI11");
}

}  // namespace
