#include "fault_point.hpp"

#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <map>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad::run {

void fault_point(const char* name) {
  // "ACTION@NAME:K", read once.
  static const std::string wanted = [] {
    const char* text = std::getenv("PHYSGRAD_FAULT");
    return text == nullptr ? std::string() : std::string(text);
  }();
  if (wanted.empty()) return;
  const std::size_t at = wanted.find('@');
  const std::size_t colon = wanted.find(':');
  if (at == std::string::npos || wanted.substr(at + 1, colon - at - 1) != name) return;
  static std::map<std::string, long> passes;
  const long k = colon == std::string::npos ? 1 : std::atol(wanted.c_str() + colon + 1);
  if (++passes[name] != k) return;
  if (wanted.compare(0, at, "kill") == 0) ::kill(::getpid(), SIGKILL);
  if (wanted.compare(0, at, "stop") == 0) ::raise(SIGSTOP);
  if (wanted.compare(0, at, "fail") == 0) {
    throw Error(std::string("injected failure at ") + name + " " + std::to_string(k));
  }
}

}  // namespace physgrad::run
