#include "physgrad/report/page_spool.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <system_error>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

[[noreturn]] void spool_failure(const std::string& what, const std::string& folder, int err) {
  throw Error("cannot " + what + " a temporary file in '" + folder +
              "': " + std::generic_category().message(err));
}

}  // namespace

PageSpool::PageSpool(const std::filesystem::path& folder) : folder_(folder.string()) {
  const std::string where = folder.empty() ? "." : folder.string();
  fd_ = ::open(where.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd_ < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
    // A file system without unnamed files: a named one, removed at once.
    std::string name = where + "/.page-spool-XXXXXX";
    fd_ = ::mkostemp(name.data(), O_CLOEXEC);
    if (fd_ >= 0) ::unlink(name.c_str());
  }
  if (fd_ < 0) spool_failure("make", folder_, errno);
}

PageSpool::~PageSpool() {
  if (fd_ >= 0) ::close(fd_);
}

void PageSpool::append(Part& part, std::string_view text) {
  if (text.empty()) return;
  const std::uint64_t at = size_;
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::pwrite(fd_, text.data() + done, text.size() - done,
                               static_cast<off_t>(at + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) spool_failure("write", folder_, errno);
    done += static_cast<std::size_t>(n);
  }
  size_ += text.size();
  if (!part.pieces.empty() && part.pieces.back().first + part.pieces.back().second == at) {
    part.pieces.back().second += text.size();
  } else {
    part.pieces.emplace_back(at, text.size());
  }
}

void PageSpool::copy(const Part& part, const std::function<void(std::string_view)>& sink) const {
  constexpr std::uint64_t kBlock = std::uint64_t{64} << 10;
  std::string buffer(kBlock, '\0');
  for (const auto& [offset, length] : part.pieces) {
    for (std::uint64_t done = 0; done < length;) {
      const std::uint64_t want = std::min(kBlock, length - done);
      const ssize_t n = ::pread(fd_, buffer.data(), want, static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) spool_failure("read", folder_, n < 0 ? errno : EIO);
      sink(std::string_view(buffer.data(), static_cast<std::size_t>(n)));
      done += static_cast<std::uint64_t>(n);
    }
  }
}

}  // namespace physgrad
