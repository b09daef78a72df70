#include "ranks.hpp"

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <thread>

#include "physgrad/error.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/text.hpp"

#ifdef PHYSGRAD_WITH_MPI
#include "physgrad/parallel/mpi_communicator.hpp"
#endif

namespace physgrad::cli {

namespace {

constexpr int kErrorExit = 2;
// How long a rank other than 0 that lost contact waits for rank 0 to save its checkpoint and end
// the job before it ends the job itself.
constexpr auto kWriterGrace = std::chrono::seconds(5);

std::shared_ptr<Communicator>& current() {
  static std::shared_ptr<Communicator> communicator = std::make_shared<SerialCommunicator>();
  return communicator;
}

double& time_limit() {
  static double seconds = kDefaultRankTimeout;
  return seconds;
}

// A setting as the ranks compare it: a text or number as written, a list comma-separated.
std::string setting_text(const nlohmann::json& value) {
  if (value.is_null()) return "unset";
  if (value.is_string()) return value.get<std::string>();
  if (!value.is_array()) return value.dump();
  std::string text;
  for (const nlohmann::json& item : value) {
    if (!text.empty()) text += ',';
    text += item.is_string() ? item.get<std::string>() : item.dump();
  }
  return text;
}

}  // namespace

void print_error(const std::string& message) {
  std::cout.flush();
  std::cerr << "physgrad: error: " + rank_prefix() + one_line(message) + "\n";
  std::cerr.flush();
}

Ranks::Ranks([[maybe_unused]] int* argc, [[maybe_unused]] char*** argv) {
#ifdef PHYSGRAD_WITH_MPI
  if (launched_by_mpi()) {
    try {
      time_limit() = rank_timeout_seconds();
    } catch (const Error& e) {
      std::cerr << "physgrad: error: " + one_line(e.what()) + "\n";
      std::exit(kErrorExit);  // before MPI_Init: the launcher ends the other ranks
    }
    current() = mpi_world_communicator(argc, argv, time_limit());
  }
#else
  // Several copies of a build without MPI would each train alone and race for the run folder.
  if (launcher_size() > 1) {
    std::cerr << "physgrad: error: this physgrad was built without MPI (PHYSGRAD_WITH_MPI off or "
                 "no MPI found), so it cannot share a run among "
              << launcher_size() << " processes; run it without mpirun\n";
    std::exit(kErrorExit);
  }
#endif
}

Ranks::~Ranks() {
  std::cout.flush();
  current() = std::make_shared<SerialCommunicator>();  // the last reference: MPI_Finalize
}

const std::shared_ptr<Communicator>& communicator() { return current(); }

bool is_writer() { return current()->rank() == 0; }

std::string rank_prefix() {
  const Communicator& c = *current();
  if (c.size() == 1) return {};
  return "rank " + std::to_string(c.rank()) + " of " + std::to_string(c.size()) + ": ";
}

std::string rank_timeout_text() {
  std::ostringstream text;
  text << time_limit();
  return text.str();
}

RankCommand rank_command(int argc, char** argv, const run::Experiment* experiment,
                         const run::Settings* settings) {
  RankCommand command;
  if (experiment != nullptr && settings != nullptr) {
    command.emplace_back("the command", "run " + experiment->name());
    for (const auto& [name, value] : settings->json().items()) {
      command.emplace_back("--" + name, setting_text(value));
    }
  } else {
    std::string arguments;
    for (int i = 1; i < argc; ++i) {
      if (i > 1) arguments += ' ';
      arguments += argv[i];
    }
    command.emplace_back("the command", arguments);
  }
  command.emplace_back("PHYSGRAD_RANK_TIMEOUT", rank_timeout_text());
  return command;
}

int require_same_command(const RankCommand& command) {
  try {
    physgrad::require_same_command(*current(), command);
  } catch (const RanksNotAnswering& e) {
    print_error(e.what());
    return end_run(kErrorExit);
  } catch (const Error& e) {
    print_error(e.what());  // every rank prints it and ends: nothing is left waiting
    return kErrorExit;
  }
  return 0;
}

int end_run(int exit_code) {
  if (current()->size() > 1) {
    std::cout.flush();
    std::cerr.flush();
    if (!is_writer() && !current()->failure().empty()) std::this_thread::sleep_for(kWriterGrace);
    current()->abort(exit_code);
  }
  return exit_code;
}

int finish(int exit_code) {
  Communicator& c = *current();
  if (c.size() == 1) return exit_code;
  if (!c.failure().empty()) return end_run(exit_code);
  try {
    wait_for_all_ranks(c);
  } catch (const RanksNotAnswering& e) {
    print_error(std::string("the ranks did not come to the end of the job together: ") + e.what());
    return end_run(kErrorExit);
  }
  return exit_code;
}

}  // namespace physgrad::cli
