#include "physgrad/report/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <string>
#include <system_error>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& step, int err) {
  throw Error("write_file_atomic: cannot " + step + " for '" + path.string() +
              "': " + std::generic_category().message(err));
}

// Opens a new file next to `path` whose name no one else uses (O_EXCL); sets `temp` to it.
int create_temp(const std::filesystem::path& path, std::filesystem::path& temp) {
  static std::atomic<unsigned> counter{0};
  const std::string stem =
      std::string(".") + path.filename().string() + ".tmp" + std::to_string(::getpid());
  for (int attempt = 0; attempt < 100; ++attempt) {
    temp = path.parent_path() / (stem + "-" + std::to_string(counter++));
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;  // errno is EEXIST
}

// Closes `fd` unless it is -1, removes the temporary file and throws for `step`.
[[noreturn]] void abandon(const std::filesystem::path& path, const std::filesystem::path& temp,
                          int fd, const std::string& step) {
  const int err = errno;
  if (fd >= 0) ::close(fd);
  ::unlink(temp.c_str());
  fail(path, step + " " + temp.string(), err);
}

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

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  std::filesystem::path temp;
  const int fd = create_temp(path, temp);
  if (fd < 0) fail(path, "create a temporary file", errno);
  for (std::size_t done = 0; done < content.size();) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) abandon(path, temp, fd, "write");
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) abandon(path, temp, fd, "flush");
  if (::close(fd) != 0) abandon(path, temp, -1, "close");
  if (::rename(temp.c_str(), path.c_str()) != 0) abandon(path, temp, -1, "rename");

  // Make the rename itself durable; the content is already complete, so this is best effort.
  sync_directory(path.parent_path().empty() ? "." : path.parent_path());
}

void sync_directory(const std::filesystem::path& folder) noexcept {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace physgrad
