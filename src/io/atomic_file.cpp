#include "physgrad/io/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <string>
#include <system_error>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

// A write into one folder: the target's name, the temporary file's, and the way out on failure.
class AtomicWrite {
 public:
  AtomicWrite(const FolderHandle& folder, std::string_view name) : folder_(folder), name_(name) {
    if (name_.empty() || name_ == "." || name_ == ".." || name_.find('/') != std::string::npos) {
      throw Error("write_file_atomic: '" + name_ + "' is not a plain file name (in '" +
                  folder.shown() + "')");
    }
  }

  // Opens a new file next to the target whose name no one else uses (O_EXCL).
  int create_temp() {
    static std::atomic<unsigned> counter{0};
    const std::string stem = "." + name_ + ".tmp" + std::to_string(::getpid()) + "-";
    for (int attempt = 0; attempt < 100; ++attempt) {
      temp_ = stem + std::to_string(counter++);
      const int fd = ::openat(folder_.fd(), temp_.c_str(),
                              O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
      if (fd >= 0) return fd;
      if (errno != EEXIST) break;
    }
    temp_.clear();
    fail("create a temporary file", errno);
  }

  // Closes `fd` unless it is -1, removes the temporary file and throws for `step`.
  [[noreturn]] void abandon(int fd, const std::string& step) {
    const int err = errno;
    if (fd >= 0) ::close(fd);
    ::unlinkat(folder_.fd(), temp_.c_str(), 0);
    abandoned_ = true;
    fail(step + " " + folder_.shown(temp_), err);
  }

  // Closes `fd` and removes the temporary file, for a write given up by its caller (unless
  // abandon() did already).
  void discard(int fd) {
    if (abandoned_) return;
    ::close(fd);
    ::unlinkat(folder_.fd(), temp_.c_str(), 0);
  }

  void rename_into_place() {
    if (::renameat(folder_.fd(), temp_.c_str(), folder_.fd(), name_.c_str()) != 0) {
      abandon(-1, "rename");
    }
  }

 private:
  [[noreturn]] void fail(const std::string& step, int err) const {
    throw Error("write_file_atomic: cannot " + step + " for '" + folder_.shown(name_) +
                "': " + std::generic_category().message(err));
  }

  const FolderHandle& folder_;
  std::string name_;
  std::string temp_;
  bool abandoned_ = false;
};

}  // namespace

bool is_atomic_write_temp(std::string_view name) {
  // "." NAME ".tmp" PID "-" N, with NAME non-empty.
  const std::size_t tmp = name.rfind(".tmp");
  if (name.size() < 2 || name[0] != '.' || tmp == std::string_view::npos || tmp < 2) return false;
  const std::string_view numbers = name.substr(tmp + 4);
  const std::size_t dash = numbers.find('-');
  const auto digits = [](std::string_view text) {
    return !text.empty() && text.find_first_not_of("0123456789") == std::string_view::npos;
  };
  return dash != std::string_view::npos && digits(numbers.substr(0, dash)) &&
         digits(numbers.substr(dash + 1));
}

namespace {

// The whole of write_file_atomic: the pieces `produce` gives written to the temporary file in
// turn, then flushed and renamed over the target.
void write_pieces_atomic(const FolderHandle& folder, std::string_view name,
                         const std::function<void(const ContentSink&)>& produce) {
  AtomicWrite write(folder, name);
  const int fd = write.create_temp();
  const auto write_out = [&](std::string_view content) {
    for (std::size_t done = 0; done < content.size();) {
      const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) write.abandon(fd, "write");
      done += static_cast<std::size_t>(n);
    }
  };
  // Small pieces are gathered into writes of at least 64 KiB.
  constexpr std::size_t kGathered = std::size_t{64} << 10;
  std::string gathered;
  const ContentSink sink = [&](std::string_view content) {
    if (gathered.size() + content.size() < kGathered) {
      gathered += content;
      return;
    }
    write_out(gathered);
    gathered.clear();
    write_out(content);
  };
  try {
    produce(sink);
  } catch (...) {
    write.discard(fd);
    throw;
  }
  write_out(gathered);
  if (::fsync(fd) != 0) write.abandon(fd, "flush");
  if (::close(fd) != 0) write.abandon(-1, "close");
  write.rename_into_place();
  // Make the rename itself durable; the content is already complete, so this is best effort.
  folder.sync();
}

FolderHandle parent_folder(const std::filesystem::path& path) {
  const std::filesystem::path parent = path.parent_path();
  const int fd = ::open(parent.empty() ? "." : parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw Error("write_file_atomic: cannot open the folder for '" + path.string() +
                "': " + std::generic_category().message(err));
  }
  return FolderHandle(fd, parent.string());
}

}  // namespace

void write_file_atomic(const FolderHandle& folder, std::string_view name,
                       std::string_view content) {
  write_pieces_atomic(folder, name, [&](const ContentSink& sink) { sink(content); });
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  write_file_atomic(parent_folder(path), path.filename().string(), content);
}

void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const ContentSink&)>& produce) {
  write_pieces_atomic(parent_folder(path), path.filename().string(), produce);
}

}  // namespace physgrad
