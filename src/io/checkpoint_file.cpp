#include "physgrad/io/checkpoint_file.hpp"

#include <cstdio>
#include <sstream>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/io/json_file.hpp"
#include "physgrad/io/atomic_file.hpp"

namespace physgrad {

namespace {

constexpr const char* kMagic = "physgrad-checkpoint";
constexpr int kVersion = 1;
// What a checkpoint may hold: nesting as deep as a trainer state's with room to spare, and
// θ and the rule's state of a network of some ten million weights.
constexpr std::size_t kMaxDepth = 64;
constexpr std::size_t kMaxBytes = std::size_t{4} << 30;

std::string hex64(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// The file's bytes: the header line, then the document.
std::string checkpoint_text(const nlohmann::json& document) {
  const std::string body = document.dump();
  return std::string(kMagic) + " " + std::to_string(kVersion) + " " +
         std::to_string(body.size()) + " " + hex64(fnv1a64(body)) + "\n" + body;
}

// Reads the bytes with `read` and checks them; errors name the checkpoint `source`.
template <class Read>
nlohmann::json read_checkpoint(const std::string& source, const Read& read) {
  std::string content;
  try {
    content = read();
  } catch (const Error& e) {
    throw Error("checkpoint '" + source + "': " + e.what());
  }
  return parse_checkpoint(content, source);
}

}  // namespace

void write_checkpoint_file(const std::filesystem::path& path, const nlohmann::json& document) {
  write_file_atomic(path, checkpoint_text(document));
}

void write_checkpoint_file(const FolderHandle& folder, const std::string& name,
                           const nlohmann::json& document) {
  write_file_atomic(folder, name, checkpoint_text(document));
}

nlohmann::json parse_checkpoint(std::string_view text, const std::string& source) {
  const auto fail = [&source](const std::string& problem) -> Error {
    return Error("checkpoint '" + source + "': " + problem);
  };
  const std::size_t newline = text.find('\n');
  std::istringstream header(std::string(text.substr(0, std::min(newline, std::size_t{200}))));
  std::string magic, checksum;
  long long version = 0, length = -1;
  header >> magic >> version >> length >> checksum;
  // Only the canonical spelling of the header is accepted, so any changed byte in it shows.
  if (newline == std::string::npos || header.fail() || magic != kMagic || length < 0 ||
      checksum.size() != 16 ||
      text.substr(0, newline) != std::string(kMagic) + " " + std::to_string(version) + " " +
                                     std::to_string(length) + " " + checksum) {
    throw fail("not a physgrad checkpoint (bad header line)");
  }
  if (version != kVersion) {
    throw fail("format version " + std::to_string(version) + ", this build reads version " +
               std::to_string(kVersion));
  }
  const std::string_view body = text.substr(newline + 1);
  if (static_cast<long long>(body.size()) != length) {
    throw fail(static_cast<long long>(body.size()) < length
                   ? "truncated (" + std::to_string(body.size()) + " of " +
                         std::to_string(length) + " bytes)"
                   : "longer than its stated " + std::to_string(length) + " bytes");
  }
  if (hex64(fnv1a64(body)) != checksum) throw fail("checksum mismatch: the file is corrupted");
  try {
    return parse_json_text(body, kMaxDepth);
  } catch (const Error& e) {
    throw fail(e.what());
  }
}

nlohmann::json read_checkpoint_file(const std::filesystem::path& path) {
  return read_checkpoint(path.string(), [&] { return read_regular_file(path, kMaxBytes); });
}

nlohmann::json read_checkpoint_file(const FolderHandle& folder, const std::string& name) {
  return read_checkpoint(folder.shown(name),
                         [&] { return read_regular_file(folder, name, kMaxBytes); });
}

}  // namespace physgrad
