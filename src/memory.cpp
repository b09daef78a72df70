#include "physgrad/memory.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

// A resource limit's room left after `used` bytes; unlimited as the largest size.
std::size_t room(int resource, std::size_t used) {
  rlimit limit{};
  if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) {
    return std::numeric_limits<std::size_t>::max();
  }
  const auto bound = static_cast<std::size_t>(limit.rlim_cur);
  return bound > used ? bound - used : 0;
}

}  // namespace

std::size_t available_memory_bytes() {
  const long page = sysconf(_SC_PAGESIZE);
  const long pages = sysconf(_SC_PHYS_PAGES);
  std::size_t available = std::numeric_limits<std::size_t>::max();
  if (page > 0 && pages > 0) {
    available = static_cast<std::size_t>(page) * static_cast<std::size_t>(pages);
  }
  // /proc/self/statm: total mapped pages first, data (+ stack) pages sixth.
  std::size_t mapped = 0, resident = 0, shared = 0, text = 0, library = 0, data = 0;
  std::ifstream statm("/proc/self/statm");
  statm >> mapped >> resident >> shared >> text >> library >> data;
  const auto page_bytes = static_cast<std::size_t>(std::max(page, 1L));
  available = std::min(available, room(RLIMIT_AS, mapped * page_bytes));
  available = std::min(available, room(RLIMIT_DATA, data * page_bytes));
  return available;
}

std::string format_bytes(double bytes) {
  static const char* const units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  std::size_t unit = 0;
  while (bytes >= 1024 && unit + 1 < std::size(units)) {
    bytes /= 1024;
    ++unit;
  }
  // Three significant digits, rounded down: an amount just short of 128 MiB does not read 128.
  const double scale = bytes >= 100 ? 1 : bytes >= 10 ? 10 : 100;
  const double shown = std::floor(bytes * scale) / scale;
  char text[48];
  std::snprintf(text, sizeof text, unit == 0 ? "%.0f %s" : "%.3g %s", shown, units[unit]);
  return text;
}

void require_memory(double bytes, const std::string& what) {
  const std::size_t available = available_memory_bytes();
  if (std::isfinite(bytes) && bytes <= static_cast<double>(available)) return;
  throw Error(what + " needs " + (std::isfinite(bytes) ? format_bytes(bytes) : "unbounded memory") +
              ", more than the " + format_bytes(static_cast<double>(available)) +
              " this process may use");
}

}  // namespace physgrad
