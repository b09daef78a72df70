// write_file_atomic — replaces a file's content all at once: the target either keeps its old
// content or has the new one, never a partial write (temp file, fsync, rename).
#pragma once

#include <filesystem>
#include <string_view>

namespace physgrad {

// Writes `content` to a fresh file next to `path`, flushes it to disk and renames it over
// `path`. On failure the temporary file is removed and an Error names the path and the reason.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace physgrad
