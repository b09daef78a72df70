// FolderHandle — an open folder (an O_DIRECTORY descriptor) whose entries are made, read, renamed
// and removed by name relative to it (openat, mkdirat, renameat, unlinkat), never by path.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace physgrad {

// What is written through a handle lands in the folder it opened, even when that folder's path is
// renamed or another folder is put in its place meanwhile. Owns its descriptor; move-only.
class FolderHandle {
 public:
  FolderHandle() = default;  // no folder
  // Takes over `fd`, an open descriptor of a folder; `shown` names the folder in messages.
  FolderHandle(int fd, std::string shown) noexcept : fd_(fd), shown_(std::move(shown)) {}
  // Opens the folder `path` (symbolic links followed). Throws Error "'SHOWN': cannot open the
  // folder: REASON".
  static FolderHandle open(const std::filesystem::path& path, std::string shown);

  FolderHandle(FolderHandle&& other) noexcept;
  FolderHandle& operator=(FolderHandle&& other) noexcept;
  FolderHandle(const FolderHandle&) = delete;
  FolderHandle& operator=(const FolderHandle&) = delete;
  ~FolderHandle();

  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  const std::string& shown() const { return shown_; }
  // "SHOWN/NAME": an entry as messages name it.
  std::string shown(std::string_view name) const;

  // True when `path` leads to this very folder now (same device and inode).
  bool is_at(const std::filesystem::path& path) const;
  // The entry `name` as a folder (a symbolic link is not followed). Throws Error.
  FolderHandle open_folder(const std::string& name) const;
  // The entries' names, without "." and "..". Throws Error naming the folder.
  std::vector<std::string> names() const;
  // Removes the entry `name`, a folder with everything in it (links are removed, not followed);
  // best effort, errors are ignored.
  void remove_all(const std::string& name) const noexcept;
  // Flushes the folder's entries (a rename or removal inside it) to disk; best effort.
  void sync() const noexcept;

 private:
  int fd_ = -1;
  std::string shown_;
};

}  // namespace physgrad
