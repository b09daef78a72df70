// write_file_atomic — replaces a file's content all at once: the target either keeps its old
// content or has the new one, never a partial write (temp file, fsync, rename).
#pragma once

#include <filesystem>
#include <string_view>

namespace physgrad {

// Writes `content` to a fresh file next to `path`, flushes it to disk and renames it over
// `path`. On failure the temporary file is removed and an Error names the path and the reason.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// Flushes a folder's entries (a rename or removal inside it) to disk; best effort.
void sync_directory(const std::filesystem::path& folder) noexcept;

// True for the name of a temporary file that write_file_atomic() makes next to its target
// (".NAME.tmpPID-N"); one left behind by a killed process can be removed by the folder's owner.
bool is_atomic_write_temp(std::string_view file_name);

}  // namespace physgrad
