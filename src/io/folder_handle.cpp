#include "physgrad/io/folder_handle.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

[[noreturn]] void fail(const std::string& shown, const std::string& step, int err) {
  throw Error("'" + shown + "': cannot " + step + ": " + std::strerror(err));
}

}  // namespace

FolderHandle FolderHandle::open(const std::filesystem::path& path, std::string shown) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) fail(shown, "open the folder", errno);
  return FolderHandle(fd, std::move(shown));
}

FolderHandle::FolderHandle(FolderHandle&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), shown_(std::move(other.shown_)) {}

FolderHandle& FolderHandle::operator=(FolderHandle&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    shown_ = std::move(other.shown_);
  }
  return *this;
}

FolderHandle::~FolderHandle() {
  if (fd_ >= 0) ::close(fd_);
}

std::string FolderHandle::shown(std::string_view name) const {
  if (shown_.empty()) return std::string(name);
  return shown_ + (shown_.back() == '/' ? "" : "/") + std::string(name);
}

bool FolderHandle::is_at(const std::filesystem::path& path) const {
  struct stat held {}, now {};
  return ::fstat(fd_, &held) == 0 && ::stat(path.c_str(), &now) == 0 &&
         held.st_dev == now.st_dev && held.st_ino == now.st_ino;
}

FolderHandle FolderHandle::open_folder(const std::string& name) const {
  const int fd = ::openat(fd_, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) fail(shown(name), "open the folder", errno);
  return FolderHandle(fd, shown(name));
}

std::vector<std::string> FolderHandle::names() const {
  // A descriptor of its own for the listing: readdir moves the position of the one it reads.
  const int fd = ::openat(fd_, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) fail(shown_, "list the folder", errno);
  const std::unique_ptr<DIR, int (*)(DIR*)> listing(::fdopendir(fd), ::closedir);
  if (!listing) {
    const int err = errno;
    ::close(fd);
    fail(shown_, "list the folder", err);
  }
  std::vector<std::string> names;
  while (true) {
    errno = 0;  // readdir returns null at the end and on an error, which sets errno
    const dirent* entry = ::readdir(listing.get());
    if (entry == nullptr) break;
    const std::string name = entry->d_name;
    if (name != "." && name != "..") names.push_back(name);
  }
  if (errno != 0) fail(shown_, "list the folder", errno);
  return names;
}

void FolderHandle::remove_all(const std::string& name) const noexcept {
  if (::unlinkat(fd_, name.c_str(), 0) == 0 || (errno != EISDIR && errno != EPERM)) return;
  try {
    const FolderHandle inner = open_folder(name);
    for (const std::string& entry : inner.names()) inner.remove_all(entry);
  } catch (const std::exception&) {
  }
  ::unlinkat(fd_, name.c_str(), AT_REMOVEDIR);
}

void FolderHandle::sync() const noexcept {
  if (fd_ >= 0) ::fsync(fd_);
}

}  // namespace physgrad
