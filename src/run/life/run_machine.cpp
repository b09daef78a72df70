#include "physgrad/run/life/run_machine.hpp"

#include <dlfcn.h>

#include <chrono>
#include <ctime>
#include <fstream>
#include <thread>

#include "physgrad/threads.hpp"

#ifndef PHYSGRAD_GIT_COMMIT
#define PHYSGRAD_GIT_COMMIT "unknown"
#endif

namespace physgrad::run {

namespace {

// The first "model name" line of /proc/cpuinfo, else "unknown".
std::string machine_cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) != 0) continue;
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::size_t start = line.find_first_not_of(" \t", colon + 1);
    if (start != std::string::npos) return line.substr(start);
  }
  return "unknown";
}

// OpenBLAS's configuration ("OpenBLAS 0.3.21 DYNAMIC_ARCH NO_AFFINITY …"), looked up at run time
// as threads.cpp does; "unknown" for another BLAS.
std::string machine_blas_library() {
  using Getter = char* (*)();
  const auto getter = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "openblas_get_config"));
  const char* config = getter == nullptr ? nullptr : getter();
  std::string text = config == nullptr ? "unknown" : config;
  while (!text.empty() && (text.back() == ' ' || text.back() == '\n')) text.pop_back();
  return text;
}

}  // namespace

nlohmann::json run_machine() {
  const std::string kernel = blas_core();
  return {{"commit", std::string(PHYSGRAD_GIT_COMMIT).empty() ? "unknown" : PHYSGRAD_GIT_COMMIT},
          {"cpu", machine_cpu_model()},
          {"blas", machine_blas_library()},
          {"blas_kernel", kernel.empty() ? "unknown" : kernel},
          {"blas_threads", blas_threads()},
          {"jacobian_threads", jacobian_threads()},
          {"hardware_threads", std::thread::hardware_concurrency()},
          {"date", utc_minute_now()}};
}

std::string run_machine_text(const nlohmann::json& machine) {
  const auto text = [&](const char* key) {
    const nlohmann::json& v = machine.contains(key) ? machine.at(key) : nlohmann::json("unknown");
    return v.is_string() ? v.get<std::string>() : v.dump();
  };
  return "commit " + text("commit") + " · CPU " + text("cpu") + " · BLAS " + text("blas") +
         " (kernel " + text("blas_kernel") + ") · threads: BLAS " + text("blas_threads") +
         ", Jacobian " + text("jacobian_threads") + ", hardware " + text("hardware_threads") +
         " · " + text("date");
}

std::string utc_minute_now() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &utc);
  return text;
}

}  // namespace physgrad::run
