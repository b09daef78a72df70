// write_file_atomic — replaces a file's content all at once: the target either keeps its old
// content or has the new one, never a partial write (temp file, fsync, rename, fsync folder).
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

#include "physgrad/io/folder_handle.hpp"

namespace physgrad {

// Writes `content` to a fresh file in `folder` (created with O_EXCL), flushes it to disk, renames
// it over the entry `name` and flushes the folder, all through the folder's handle: the file
// lands in that folder whatever its path leads to meanwhile. `name` is a plain file name (no
// '/'). On failure the temporary file is removed and an Error names the file and the reason.
void write_file_atomic(const FolderHandle& folder, std::string_view name,
                       std::string_view content);
// The same for the file at `path`, in the folder its parent path opens.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);
// The same with the content given in pieces, for one too large to hold at once: `produce` calls
// its argument with each piece in turn. When `produce` throws, the temporary file is removed and
// the exception passes on; the target keeps its old content.
using ContentSink = std::function<void(std::string_view)>;
void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const ContentSink&)>& produce);

// True for the name of a temporary file that write_file_atomic() makes next to its target
// (".NAME.tmpPID-N"); one left behind by a killed process can be removed by the folder's owner.
bool is_atomic_write_temp(std::string_view file_name);

}  // namespace physgrad
