// Checkpoint files: a JSON document behind one header line that gives the format version, the
// document's length in bytes and its FNV-1a 64-bit checksum,
//   physgrad-checkpoint 1 <length> <checksum as 16 hex digits>\n<document>
// so a truncated, extended or corrupted file is recognised instead of being half-read.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "physgrad/io/folder_handle.hpp"
#include "physgrad/io/hash.hpp"

namespace physgrad {

// Writes atomically (temporary file, fsync, rename): the file holds the old or the new
// checkpoint, never a mix. Throws Error naming the path when it cannot.
void write_checkpoint_file(const std::filesystem::path& path, const nlohmann::json& document);
// The same for the file `name` in `folder`, written through the folder's handle.
void write_checkpoint_file(const FolderHandle& folder, const std::string& name,
                           const nlohmann::json& document);

// Throws Error "checkpoint 'PATH': …" when the file is missing, is not a regular file (read
// without blocking on a FIFO or device), is larger than 4 GiB, is not a checkpoint, has another
// version, is truncated or longer than stated, fails its checksum, holds invalid JSON, or nests
// deeper than 64 levels.
nlohmann::json read_checkpoint_file(const std::filesystem::path& path);
// The same for the file `name` in `folder`, opened through the folder's handle; errors name it
// "checkpoint 'FOLDER/NAME': …".
nlohmann::json read_checkpoint_file(const FolderHandle& folder, const std::string& name);
// The same checks on a checkpoint's bytes; `source` names it in errors.
nlohmann::json parse_checkpoint(std::string_view text, const std::string& source);

}  // namespace physgrad
