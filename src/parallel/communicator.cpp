#include "physgrad/parallel/communicator.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"

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

namespace {

// `command` as bytes: each text preceded by its length (8 bytes).
std::string encode_command(const RankCommand& command) {
  std::string bytes;
  const auto put = [&bytes](const std::string& text) {
    const auto length = static_cast<std::uint64_t>(text.size());
    bytes.append(reinterpret_cast<const char*>(&length), sizeof(length));
    bytes += text;
  };
  for (const auto& [name, value] : command) {
    put(name);
    put(value);
  }
  return bytes;
}

RankCommand decode_command(const std::string& bytes) {
  RankCommand command;
  std::size_t at = 0;
  const auto take = [&bytes, &at] {
    std::uint64_t length = 0;
    if (bytes.size() - at < sizeof(length)) throw Error("a rank sent a malformed command");
    std::memcpy(&length, bytes.data() + at, sizeof(length));
    at += sizeof(length);
    if (bytes.size() - at < length) throw Error("a rank sent a malformed command");
    std::string text = bytes.substr(at, static_cast<std::size_t>(length));
    at += static_cast<std::size_t>(length);
    return text;
  };
  while (at < bytes.size()) {
    std::string name = take();
    command.emplace_back(std::move(name), take());
  }
  return command;
}

// "NAME is 'A' on rank 0 but 'B' on rank R" for the first entry in which rank R differs from
// rank 0, or empty.
std::string first_difference(const RankCommand& first, const RankCommand& other, int rank) {
  const auto value_in = [](const RankCommand& command, const std::string& name) {
    for (const auto& [key, value] : command) {
      if (key == name) return in_quotes(value);
    }
    return std::string("not given");
  };
  const auto differs = [&](const std::string& name, const std::string& a, const std::string& b) {
    return name + " is " + a + " on rank 0 but " + b + " on rank " + std::to_string(rank);
  };
  for (const auto& [name, value] : first) {
    const std::string theirs = value_in(other, name);
    if (theirs != in_quotes(value)) return differs(name, in_quotes(value), theirs);
  }
  for (const auto& [name, value] : other) {
    if (value_in(first, name) == "not given") return differs(name, "not given", in_quotes(value));
  }
  return {};
}

}  // namespace

void require_same_command(Communicator& communicator, const RankCommand& command) {
  if (communicator.size() == 1) return;
  // The bytes travel in doubles (no arithmetic is done on them), after their count.
  const std::string bytes = encode_command(command);
  std::vector<double> packed(1 + (bytes.size() + sizeof(double) - 1) / sizeof(double), 0.0);
  packed[0] = static_cast<double>(bytes.size());
  std::memcpy(packed.data() + 1, bytes.data(), bytes.size());
  std::vector<std::size_t> counts;
  const std::vector<double> all = communicator.allgather(packed.data(), packed.size(), &counts);
  std::vector<RankCommand> commands;
  std::size_t at = 0;
  for (const std::size_t count : counts) {
    const auto length = static_cast<std::size_t>(all.at(at));
    if (count == 0 || (count - 1) * sizeof(double) < length) {
      throw Error("a rank sent a malformed command");
    }
    commands.push_back(
        decode_command(std::string(reinterpret_cast<const char*>(all.data() + at + 1), length)));
    at += count;
  }
  for (std::size_t r = 1; r < commands.size(); ++r) {
    const std::string difference = first_difference(commands[0], commands[r], static_cast<int>(r));
    if (!difference.empty()) {
      throw Error("the ranks were not started alike: " + difference +
                  "; start every rank with the same command and settings");
    }
  }
}

void wait_for_all_ranks(Communicator& communicator) { communicator.allreduce_sum(0.0); }

double rank_timeout_seconds() {
  const char* text = std::getenv("PHYSGRAD_RANK_TIMEOUT");
  if (text == nullptr) return kDefaultRankTimeout;
  const std::string value = text;
  double seconds = NAN;
  const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), seconds);
  if (error != std::errc() || end != value.data() + value.size() || !(seconds > 0) ||
      !(seconds <= 1e6)) {
    throw Error("PHYSGRAD_RANK_TIMEOUT: " + in_quotes(value) +
                " is not a number of seconds in (0, 1e6] (like 300 or 2.5)");
  }
  return seconds;
}

}  // namespace physgrad
