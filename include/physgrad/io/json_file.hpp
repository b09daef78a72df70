// Reading JSON a user hands over (config files, checkpoints): all of a regular file of ≤ N bytes,
// parsed with nesting ≤ D levels, each key once per object, errors at "line L, column C".
#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "physgrad/io/folder_handle.hpp"

namespace physgrad {

// The bytes of `path`. A FIFO, device, socket or directory is refused without blocking on it,
// and so is a file of more than `max_bytes` bytes or one that does not fit in the memory this
// process may use. Throws Error without the path ("is a directory", "is not a regular file (a
// FIFO)", "is 5000000 bytes, more than the 1048576 allowed", "cannot open: No such file or
// directory"), for the caller to prefix.
std::string read_regular_file(const std::filesystem::path& path, std::size_t max_bytes);
// The same for the entry `name` of `folder`, opened through the folder's handle.
std::string read_regular_file(const FolderHandle& folder, const std::string& name,
                              std::size_t max_bytes);

// Parses JSON text into a document, iteratively (no recursion over the input's depth). Throws
// Error "invalid JSON at line L, column C: DETAIL" on a syntax error or a number too large for a
// double, "key 'K' appears twice", or "JSON nested deeper than D levels" (arrays and objects).
nlohmann::json parse_json_text(std::string_view text, std::size_t max_depth);

}  // namespace physgrad
