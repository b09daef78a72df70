#include "physgrad/parallel/communicator.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

std::vector<double> SerialCommunicator::allgather(const double* data, std::size_t count,
                                                  std::vector<std::size_t>* counts) {
  if (counts != nullptr) *counts = {count};
  return std::vector<double>(data, data + count);
}

void SerialCommunicator::broadcast(double* /*data*/, std::size_t /*count*/, int root) {
  if (root != 0) throw Error("broadcast: root " + std::to_string(root) + " of 1 rank");
}

Share share_of(std::size_t count, int rank, int size) {
  if (size < 1 || rank < 0 || rank >= size) {
    throw Error("share_of: rank " + std::to_string(rank) + " of " + std::to_string(size));
  }
  const auto k = static_cast<std::size_t>(size);
  const auto r = static_cast<std::size_t>(rank);
  const std::size_t base = count / k, extra = count % k;
  return {r * base + (r < extra ? r : extra), base + (r < extra ? 1 : 0)};
}

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

int launcher_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}) {
    if (const char* value = std::getenv(name)) {
      const int size = std::atoi(value);
      return size > 1 ? size : 1;
    }
  }
  return 1;
}

std::uint64_t hash_doubles(const double* data, std::size_t count) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (std::size_t i = 0; i < count; ++i) {
    unsigned char bytes[sizeof(double)];
    std::memcpy(bytes, &data[i], sizeof(double));
    for (const unsigned char byte : bytes) {
      hash ^= byte;
      hash *= 1099511628211ULL;
    }
  }
  return hash;
}

bool same_on_all_ranks(Communicator& communicator, std::uint64_t hash) {
  // The hash travels as the bytes of a double (no arithmetic is done on it).
  double word = 0;
  std::memcpy(&word, &hash, sizeof(word));
  const std::vector<double> all = communicator.allgather(&word, 1);
  for (const double other : all) {
    if (std::memcmp(&other, &word, sizeof(word)) != 0) return false;
  }
  return true;
}

}  // namespace physgrad
