#include "physgrad/io/json_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <set>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"

namespace physgrad {

namespace {

using json = nlohmann::json;

// Closes a file descriptor on every way out.
struct FileDescriptor {
  int fd;
  ~FileDescriptor() {
    if (fd >= 0) ::close(fd);
  }
};

std::string kind_of(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

// "line L, column C" of the byte after the first `position` bytes, counted as nlohmann::json does.
std::string text_position(std::string_view text, std::size_t position) {
  const std::string_view read = text.substr(0, std::min(position, text.size()));
  const auto lines = std::count(read.begin(), read.end(), '\n');
  const std::size_t last_newline = read.rfind('\n');
  const std::size_t column =
      last_newline == std::string_view::npos ? read.size() : read.size() - last_newline - 1;
  return "line " + std::to_string(lines + 1) + ", column " + std::to_string(column);
}

// nlohmann::json SAX handler building the document iteratively, so that repeated keys and deep
// nesting are caught while parsing and every parse error gets its line and column.
class DocumentBuilder {
 public:
  DocumentBuilder(std::string_view text, std::size_t max_depth)
      : text_(text), max_depth_(max_depth) {}
  json take() { return std::move(root_); }

  bool null() { return add(nullptr); }
  bool boolean(bool value) { return add(value); }
  bool number_integer(json::number_integer_t value) { return add(value); }
  bool number_unsigned(json::number_unsigned_t value) { return add(value); }
  bool number_float(json::number_float_t value, const json::string_t& /*text*/) {
    return add(value);
  }
  bool string(json::string_t& value) { return add(std::move(value)); }
  bool binary(json::binary_t& /*value*/) { return false; }  // JSON text has no binary values
  bool start_object(std::size_t /*size*/) {
    keys_.emplace_back();
    return open(json::object());
  }
  bool key(json::string_t& name) {
    if (!keys_.back().insert(name).second) throw Error("key '" + name + "' appears twice");
    key_ = std::move(name);
    return true;
  }
  bool end_object() {
    keys_.pop_back();
    open_.pop_back();
    return true;
  }
  bool start_array(std::size_t /*size*/) { return open(json::array()); }
  bool end_array() {
    open_.pop_back();
    return true;
  }
  bool parse_error(std::size_t position, const std::string& /*last_token*/,
                   const json::exception& error) {
    // what() is "[json.exception.KIND.ID] parse error at line L, column C: DETAIL" or
    // "[json.exception.KIND.ID] DETAIL"; keep DETAIL.
    std::string detail = error.what();
    detail.erase(0, detail.find("] ") + 2);
    if (detail.starts_with("parse error")) detail.erase(0, detail.find(": ") + 2);
    throw Error("invalid JSON at " + text_position(text_, position) + ": " + detail);
  }

 private:
  bool add(json value) {
    place(std::move(value));
    return true;
  }
  json* place(json value) {
    if (open_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    json& parent = *open_.back();
    if (parent.is_array()) {
      parent.push_back(std::move(value));
      return &parent.back();
    }
    return &(parent[key_] = std::move(value));
  }
  bool open(json container) {
    if (open_.size() == max_depth_) {
      throw Error("JSON nested deeper than " + std::to_string(max_depth_) + " levels");
    }
    open_.push_back(place(std::move(container)));
    return true;
  }

  std::string_view text_;
  std::size_t max_depth_;
  json root_;
  std::vector<json*> open_;  // the open arrays and objects, innermost last
  std::vector<std::set<std::string>> keys_;  // keys seen in each open object
  std::string key_;
};

}  // namespace

namespace {

// The file `name` relative to the folder `folder_fd` (AT_FDCWD: the working folder).
std::string read_regular_file_at(int folder_fd, const char* name, std::size_t max_bytes) {
  // O_NONBLOCK: opening a FIFO does not wait for a writer; it is refused below.
  const FileDescriptor file{
      ::openat(folder_fd, name, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC)};
  if (file.fd < 0) throw Error(std::string("cannot open: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(file.fd, &info) != 0) {
    throw Error(std::string("cannot read: ") + std::strerror(errno));
  }
  if (S_ISDIR(info.st_mode)) throw Error("is a directory");
  if (!S_ISREG(info.st_mode)) throw Error("is not a regular file (" + kind_of(info.st_mode) + ")");
  const auto size = static_cast<std::size_t>(info.st_size);
  if (size > max_bytes) {
    throw Error("is " + std::to_string(size) + " bytes, more than the " +
                std::to_string(max_bytes) + " allowed");
  }
  require_memory(static_cast<double>(size), "reading it");
  std::string bytes(size, '\0');
  std::size_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(file.fd, bytes.data() + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw Error(std::string("cannot read: ") + std::strerror(errno));
    if (n == 0) break;  // shrank while reading: keep what is there
    got += static_cast<std::size_t>(n);
  }
  bytes.resize(got);
  char extra = 0;
  ssize_t more = 0;
  do {
    more = ::read(file.fd, &extra, 1);
  } while (more < 0 && errno == EINTR);
  if (more > 0) throw Error("grew while being read");
  return bytes;
}

}  // namespace

std::string read_regular_file(const std::filesystem::path& path, std::size_t max_bytes) {
  return read_regular_file_at(AT_FDCWD, path.c_str(), max_bytes);
}

std::string read_regular_file(const FolderHandle& folder, const std::string& name,
                              std::size_t max_bytes) {
  return read_regular_file_at(folder.fd(), name.c_str(), max_bytes);
}

json parse_json_text(std::string_view text, std::size_t max_depth) {
  DocumentBuilder builder(text, max_depth);
  json::sax_parse(text, &builder);
  return builder.take();
}

}  // namespace physgrad
