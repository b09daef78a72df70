// PageSpool — the parts of a page too large to hold in memory (e.g. the rows of a table that
// grows with every run folder), written to an unnamed temporary file as they come and read back
// part by part in the order the page needs them. Memory: one (offset, length) per append.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace physgrad {

class PageSpool {
 public:
  // The text of one part: where its pieces lie in the file, in order.
  struct Part {
    std::vector<std::pair<std::uint64_t, std::uint64_t>> pieces;  // offset, length
    bool empty() const { return pieces.empty(); }
  };

  // An unnamed file in `folder` (gone when closed, whatever ends the process). Throws Error
  // naming the folder when none can be made.
  explicit PageSpool(const std::filesystem::path& folder);
  ~PageSpool();
  PageSpool(const PageSpool&) = delete;
  PageSpool& operator=(const PageSpool&) = delete;

  // Adds `text` to the end of `part`. Throws Error when it cannot be written (e.g. disk full).
  void append(Part& part, std::string_view text);
  // The part's text, handed to `sink` in pieces of at most 64 KiB, in order.
  void copy(const Part& part, const std::function<void(std::string_view)>& sink) const;

 private:
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::string folder_;
};

}  // namespace physgrad
