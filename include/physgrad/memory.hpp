// Memory bounds — what this process may still allocate: min(physical memory, address-space limit
// − mapped size, data limit − data size); sizes are checked against it before allocating.
#pragma once

#include <cstddef>
#include <string>

namespace physgrad {

// Bytes this process may still allocate, by the bound above (ulimit -v and -d count).
std::size_t available_memory_bytes();

// "512 B", "1.5 KiB", "7.3 TiB" (3 significant digits, rounded down).
std::string format_bytes(double bytes);

// Throws Error "WHAT needs 7.3 TiB, more than the 22 GiB this process may use" when `bytes`
// exceed available_memory_bytes() (or are not finite).
void require_memory(double bytes, const std::string& what);

}  // namespace physgrad
