// The run folder's life: located, claimed under its lock, committed or abandoned (run_folder.hpp).
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

#include "physgrad/run/life/checkpoint.hpp"
#include "physgrad/run/life/config_file.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/text.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "fault_point.hpp"

namespace physgrad::run {

namespace fs = std::filesystem;

namespace {

constexpr const char* kStaging = ".staging";
constexpr const char* kPendingSummary = ".summary.json.pending";

std::string system_reason(int err) { return std::strerror(err); }

// What a folder holds, by the names the run folder uses.
struct Contents {
  bool config = false;
  bool checkpoint = false;
  bool summary = false;
  std::vector<std::string> scratch;  // staging folder and temporary files of a killed process
  std::vector<std::string> results;  // the other files a run writes (a commit cut short)
  std::vector<std::string> other;    // anything else, sorted
  bool empty() const {
    return !config && !checkpoint && !summary && results.empty() && other.empty();
  }
  bool finished() const { return summary && !checkpoint; }
  bool unfinished() const { return config && !finished(); }
};

Contents read_contents(const FolderHandle& folder) {
  Contents contents;
  for (const std::string& name : folder.names()) {
    if (name == kConfigFile) {
      contents.config = true;
    } else if (name == kCheckpointFile) {
      contents.checkpoint = true;
    } else if (name == kSummaryFile) {
      contents.summary = true;
    } else if (name == kStaging || name == kPendingSummary || is_atomic_write_temp(name)) {
      contents.scratch.push_back(name);
    } else if (is_result_file(name)) {
      contents.results.push_back(name);
    } else {
      contents.other.push_back(name);
    }
  }
  std::sort(contents.other.begin(), contents.other.end());
  return contents;
}

void remove_scratch(const FolderHandle& folder, const Contents& contents) {
  for (const std::string& name : contents.scratch) folder.remove_all(name);
}

// Removes the folders in `folders` (innermost first) while they are empty.
void remove_empty(const std::vector<fs::path>& folders) noexcept {
  for (const fs::path& folder : folders) {
    if (::rmdir(folder.c_str()) != 0) return;
  }
}

// Creates the missing parents of `path`; returns those it made, innermost first.
std::vector<fs::path> make_parents(const fs::path& path, const std::string& option) {
  std::vector<fs::path> missing;  // innermost first
  for (fs::path p = path.parent_path(); p != p.root_path() && !p.empty(); p = p.parent_path()) {
    struct stat info {};
    if (::stat(p.c_str(), &info) == 0) break;
    missing.push_back(p);
  }
  std::vector<fs::path> created;
  for (auto p = missing.rbegin(); p != missing.rend(); ++p) {
    if (::mkdir(p->c_str(), 0777) == 0) {
      created.insert(created.begin(), *p);
    } else if (errno != EEXIST) {
      const int err = errno;
      remove_empty(created);
      throw Error(option + ": cannot create " + in_quotes(p->string()) + ": " + system_reason(err));
    }
  }
  return created;
}

// Refuses a folder inside the folder of a run: the new run would change a finished result, or
// its files would be committed with an unfinished one's. An ancestor is a run's folder when its
// config.json is one a run wrote (naming an experiment and its settings); a config.json of
// something else further up does not count.
void refuse_inside_run(const fs::path& path, const std::string& what) {
  for (fs::path p = path.parent_path(); !p.empty(); p = p.parent_path()) {
    std::error_code error;
    if (fs::is_regular_file(p / kConfigFile, error)) {
      bool a_run = false;
      try {
        const nlohmann::json config = read_config_document(p / kConfigFile);
        a_run = config.is_object() && config.contains("experiment") && config.contains("settings");
      } catch (const Error&) {
      }
      if (a_run) {
        throw Error(what + " lies inside the run folder " + in_quotes(p.string()) +
                    "; choose a folder outside it");
      }
    }
    if (p == p.root_path()) break;
  }
}

// Opens `path` and takes its lock; no handle when there is no folder there (any more). The
// identity check catches a folder removed or replaced between the open and the lock.
FolderHandle open_locked(const fs::path& path, const std::string& shown, const std::string& what) {
  for (int attempt = 0; attempt < 16; ++attempt) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) {
      const int err = errno;
      if (err == ENOENT) return {};
      throw Error(what + ": cannot open the folder: " + system_reason(err));
    }
    FolderHandle folder(fd, shown);
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      if (err == EWOULDBLOCK) {
        throw Error(what + " is in use by another physgrad process; wait for it to end or choose "
                           "another folder");
      }
      throw Error(what + ": cannot lock the folder: " + system_reason(err));
    }
    if (folder.is_at(path)) return folder;
  }
  throw Error(what + ": the folder keeps being replaced by another process");
}

}  // namespace

FolderPath locate_folder(const std::string& text, const std::string& option) {
  const std::string named = option + ": " + in_quotes(text);
  if (text.find_first_not_of(" \t\n\v\f\r") == std::string::npos) {
    throw Error(named + " is blank; name a folder");
  }
  if (const std::string problem = text_problem(text); !problem.empty()) {
    throw Error(named + " " + problem);
  }
  FolderPath where{text, {}};
  while (where.shown.size() > 1 && where.shown.back() == '/') where.shown.pop_back();
  std::error_code error;
  where.path = fs::weakly_canonical(fs::absolute(where.shown, error), error);
  if (error) throw Error(named + ": " + error.message());
  if (!where.path.has_filename()) where.path = where.path.parent_path();  // "DIR/." → "DIR/"
  struct stat info {};
  if (::lstat(where.path.c_str(), &info) == 0) {
    if (S_ISLNK(info.st_mode)) {  // weakly_canonical follows every link that leads somewhere
      throw Error(named + " is a symbolic link to " +
                  in_quotes(fs::read_symlink(where.path, error).string()) + ", which does not exist");
    }
    if (!S_ISDIR(info.st_mode)) throw Error(named + " exists and is not a directory");
  }
  return where;
}

RunFolder::RunFolder(const FolderPath& where, FolderHandle folder, bool resuming)
    : path_(where.path), folder_(std::move(folder)), resuming_(resuming) {}

RunFolder::RunFolder(RunFolder&& other) noexcept
    : path_(std::move(other.path_)),
      folder_(std::move(other.folder_)),
      staging_(std::move(other.staging_)),
      resuming_(other.resuming_),
      created_(other.created_),
      created_parents_(std::move(other.created_parents_)),
      moved_(std::move(other.moved_)),
      ended_(std::exchange(other.ended_, true)),
      ended_text_(std::move(other.ended_text_)) {}

RunFolder::~RunFolder() {
  if (!ended_) abandon();
}

RunFolder RunFolder::create(const FolderPath& out) {
  const std::string what = "--out: " + in_quotes(out.shown);
  refuse_inside_run(out.path, what);
  std::vector<fs::path> parents = make_parents(out.path, "--out");
  for (int attempt = 0; attempt < 16; ++attempt) {
    const bool made = ::mkdir(out.path.c_str(), 0777) == 0;
    if (!made && errno != EEXIST) {
      const int err = errno;
      remove_empty(parents);
      throw Error(what + ": cannot create the folder: " + system_reason(err));
    }
    FolderHandle handle;
    try {
      handle = open_locked(out.path, out.shown, what);
    } catch (const Error&) {
      remove_empty(parents);
      throw;
    }
    if (!handle.is_open()) continue;  // removed again before it could be opened
    RunFolder folder(out, std::move(handle), false);
    folder.created_ = made;
    folder.created_parents_ = std::move(parents);
    const Contents contents = read_contents(folder.folder_);
    if (!contents.empty()) {
      folder.ended_ = true;  // not ours: leave it exactly as it is
      remove_empty(folder.created_parents_);
      if (contents.finished()) {
        throw Error(what + " holds the results of a finished run; choose another folder");
      }
      if (contents.unfinished()) {
        throw Error(what + " holds an unfinished run; continue it with `physgrad resume " +
                    out.shown + "` or choose another folder");
      }
      throw Error(what + " already exists and is not empty");
    }
    remove_scratch(folder.folder_, contents);
    return folder;
  }
  remove_empty(parents);
  throw Error(what + ": the folder keeps being removed by another process");
}

RunFolder RunFolder::create_unique(const fs::path& parent, const std::string& stem) {
  const FolderPath first = locate_folder((parent / stem).string(), "--out");
  refuse_inside_run(first.path, "--out: " + in_quotes(first.shown));
  std::vector<fs::path> parents = make_parents(first.path, "--out");
  for (int n = 1; n <= 1000; ++n) {
    std::string suffix;
    if (n > 1) suffix.append("-").append(std::to_string(n));
    const FolderPath where{first.shown + suffix, fs::path(first.path.string() + suffix)};
    if (::mkdir(where.path.c_str(), 0777) != 0) {
      if (errno == EEXIST) continue;
      const int err = errno;
      remove_empty(parents);
      throw Error("--out: cannot create " + in_quotes(where.shown) + ": " + system_reason(err));
    }
    FolderHandle handle = open_locked(where.path, where.shown, "--out: " + in_quotes(where.shown));
    if (!handle.is_open()) continue;
    RunFolder folder(where, std::move(handle), false);
    folder.created_ = true;
    folder.created_parents_ = std::move(parents);
    return folder;
  }
  remove_empty(parents);
  throw Error("--out: no free folder name " + in_quotes(first.shown) + "[-N] up to N = 1000");
}

RunFolder RunFolder::reopen(const FolderPath& where) {
  const std::string what = "resume: " + in_quotes(where.shown);
  FolderHandle handle = open_locked(where.path, where.shown, what);
  if (!handle.is_open()) throw Error(what + " does not exist");
  RunFolder folder(where, std::move(handle), true);
  const Contents contents = read_contents(folder.folder_);
  folder.ended_ = true;  // until it is accepted: a refused folder is left exactly as it is
  if (contents.finished()) {
    throw Error(what + " holds a finished run (" + kSummaryFile + "); there is nothing to resume");
  }
  if (!contents.unfinished()) {
    throw Error(what + " holds no run to resume (no " + kConfigFile + ")");
  }
  if (!contents.other.empty()) {
    throw Error(what + " holds " + in_quotes(contents.other.front()) +
                ", which is no file of a run; move it out of the folder to resume the run");
  }
  folder.ended_ = false;
  remove_scratch(folder.folder_, contents);
  return folder;
}

std::string RunFolder::shown_now() const {
  if (folder_.is_at(path_)) return shown();
  // Moved since: Linux names an open folder's present path in /proc/self/fd.
  const std::string link = "/proc/self/fd/" + std::to_string(folder_.fd());
  std::string now(PATH_MAX, '\0');
  const ssize_t length = ::readlink(link.c_str(), now.data(), now.size());
  if (length <= 0 || static_cast<std::size_t>(length) >= now.size()) return shown();
  now.resize(static_cast<std::size_t>(length));
  return now.ends_with(" (deleted)") ? shown() : now;
}

void RunFolder::fail(const std::string& step, int err) const {
  throw Error(in_quotes(shown_now()) + ": cannot " + step + ": " + system_reason(err));
}

const FolderHandle& RunFolder::staging() {
  staging_ = FolderHandle();
  folder_.remove_all(kStaging);
  if (::mkdirat(folder_.fd(), kStaging, 0777) != 0) fail("create the staging folder", errno);
  staging_ = folder_.open_folder(kStaging);
  return staging_;
}

void RunFolder::commit() {
  if (!staging_.is_open()) throw Error(in_quotes(shown_now()) + ": there are no staged results");
  std::vector<std::string> names = staging_.names();
  const auto move = [&](const FolderHandle& from, const std::string& name, const std::string& to) {
    if (::renameat(from.fd(), name.c_str(), folder_.fd(), to.c_str()) != 0) {
      const int err = errno;
      fail("move " + name + " into place", err);
    }
  };
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) {
    if (name == kSummaryFile) continue;
    move(staging_, name, name);
    moved_.push_back(name);
    fault_point("commit");
  }
  // summary.json marks the folder finished: it is parked under a scratch name so that the
  // staging folder is gone before it appears.
  move(staging_, kSummaryFile, kPendingSummary);
  staging_ = FolderHandle();
  if (::unlinkat(folder_.fd(), kStaging, AT_REMOVEDIR) != 0) {
    fail("remove the staging folder", errno);
  }
  folder_.sync();
  move(folder_, kPendingSummary, kSummaryFile);
  moved_.push_back(kSummaryFile);
  folder_.sync();
  fault_point("commit");
  // The last step: without its checkpoint the folder is finished.
  if (::unlinkat(folder_.fd(), kCheckpointFile, 0) != 0 && errno != ENOENT) {
    fail("remove the checkpoint", errno);
  }
  folder_.sync();
  ended_ = true;
  ended_text_ = "finished";
}

std::string RunFolder::abandon() noexcept {
  if (ended_) return ended_text_;
  ended_ = true;
  staging_ = FolderHandle();
  folder_.remove_all(kStaging);
  try {
    const Contents contents = read_contents(folder_);
    remove_scratch(folder_, contents);
    if (contents.checkpoint) {
      ended_text_ = "checkpoint kept, continue with: physgrad resume " + shown_now();
    } else if (resuming_) {
      ended_text_ = "the folder is kept; physgrad resume " + shown_now() + " runs it again";
    } else {
      // A new run without a checkpoint: take back what this process wrote.
      ::unlinkat(folder_.fd(), kConfigFile, 0);
      for (const std::string& name : moved_) ::unlinkat(folder_.fd(), name.c_str(), 0);
      // The folder itself only while its path still leads to it: one renamed away stays, empty.
      if (created_ && folder_.is_at(path_) && ::rmdir(path_.c_str()) == 0) {
        remove_empty(created_parents_);
      }
      ended_text_ = "nothing was kept";
    }
  } catch (const std::exception& e) {
    ended_text_ = std::string("the folder could not be cleaned up: ") + e.what();
  }
  return ended_text_;
}

}  // namespace physgrad::run
