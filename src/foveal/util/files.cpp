// foveal/util/files.cpp — never over an input, all or nothing (see files.h).
#include "foveal/util/files.h"

#include "foveal/util/error.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <csignal>
#include <filesystem>
#include <mutex>
#include <optional>
#include <set>
#include <sys/stat.h>
#include <unistd.h>

namespace foveal {

namespace fs = std::filesystem;

namespace {

std::string resolved(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return ec ? fs::absolute(path).lexically_normal().string() : p.string();
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool eq = fs::equivalent(a, b, ec);  // hard links too
    if (!ec) return eq;
  }
  return resolved(a) == resolved(b);
}

// The file behind a path (device, inode), where it exists: hard links and other spellings of one file
std::optional<std::pair<dev_t, ino_t>> file_id(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  return std::make_pair(st.st_dev, st.st_ino);
}

struct Guard {
  std::mutex mutex;
  std::set<std::string> paths;              // resolved
  std::set<std::pair<dev_t, ino_t>> files;  // of the inputs that exist
  std::atomic<bool> on{false};
};
Guard& guard() {
  static Guard g;
  return g;
}

// Refuses a target that no one may write, or a folder no one may write into: read-only by intent.
// The system lets root (a container's user, often) replace such a file or add to such a folder (a
// bench's --json, run as root, replaced a read-only recording so), so foveal refuses it for every
// user.
bool read_only_folder(const fs::path& folder) {
  struct stat st {};
  return ::stat(folder.c_str(), &st) == 0 && S_ISDIR(st.st_mode) && (st.st_mode & 0222) == 0;
}
void check_not_read_only(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISDIR(st.st_mode) && (st.st_mode & 0222) == 0)
    fail("{}: is read-only; foveal does not replace a read-only file (give another name, or make it writable)", path);
  const fs::path p = fs::absolute(path).lexically_normal();
  const fs::path parent = p.has_filename() ? p.parent_path() : p.parent_path().parent_path();
  if (read_only_folder(parent))
    fail("{}: its folder {} is read-only; foveal does not write into a read-only folder", path, parent.string());
}

}  // namespace

void check_output_file(const std::string& path, const std::vector<std::string>& extensions) {
  if (path.empty()) fail("an output file needs a name");
  std::error_code ec;
  const fs::path p(path);
  if (fs::is_directory(p, ec)) fail("{}: is a folder; give a file name", path);
  if (!extensions.empty() && std::find(extensions.begin(), extensions.end(), lower_extension(path)) == extensions.end()) {
    std::string known;
    for (size_t k = 0; k < extensions.size(); ++k) known += (k == 0 ? "" : k + 1 == extensions.size() ? " or " : ", ") + extensions[k];
    fail("{}: the file name must end in {}", path, known);
  }
  const fs::path parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::exists(parent, ec)) fail("{}: the folder {} does not exist", path, parent.string());
  if (!fs::is_directory(parent, ec)) fail("{}: {} is not a folder", path, parent.string());
  check_not_read_only(path);
  if (fs::exists(p, ec) ? ::access(path.c_str(), W_OK) != 0 : ::access(parent.c_str(), W_OK | X_OK) != 0)
    fail("{}: cannot be written here ({})", path, std::strerror(errno));
}

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void check_output_is_not_input(const std::string& output, const std::string& input, const char* option) {
  if (output.empty() || input.empty()) return;
  if (same_file(output, input)) fail("{} {}: is the input {}; foveal never writes over its inputs", option, output, input);
}

void check_outputs_apart(const std::vector<OptionPath>& outputs, const std::vector<OptionPath>& arguments) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    const OptionPath& out = outputs[i];
    if (out.path.empty()) continue;
    for (size_t j = i + 1; j < outputs.size(); ++j)
      if (!outputs[j].path.empty() && same_file(out.path, outputs[j].path))
        fail("{} {} and {} {}: two outputs into one file (the second would replace the first); give each its own name", out.option,
             out.path, outputs[j].option, outputs[j].path);
    for (const OptionPath& arg : arguments) {
      std::error_code ec;
      if (arg.path.empty() || !fs::exists(arg.path, ec)) continue;
      if (same_file(out.path, arg.path))
        fail("{} {}: is {} {}, an input of this run; foveal never writes over its inputs", out.option, out.path, arg.option, arg.path);
    }
  }
}

void set_input_guard(bool on) { guard().on = on; }

void note_input(const std::string& path) {
  Guard& g = guard();
  if (!g.on) return;
  const std::string r = resolved(path);
  const auto id = file_id(path);
  const std::lock_guard lock(g.mutex);
  g.paths.insert(r);
  if (id) g.files.insert(*id);
}

// Two lookups per write, whatever the number of inputs (a folder of a thousand frames).
void check_not_an_input(const std::string& output) {
  check_not_read_only(output);
  Guard& g = guard();
  if (!g.on) return;
  const std::string r = resolved(output);
  const auto id = file_id(output);
  const std::lock_guard lock(g.mutex);
  if (g.paths.count(r) || (id && g.files.count(*id))) fail("{}: is an input of this run; foveal never writes over its inputs", output);
}

namespace {

// Where a target's partial copies go: its folder, and the prefix ".NAME.partial-" (NAME the target's
// last component, a trailing '/' aside).
std::pair<fs::path, std::string> partial_place(const std::string& target) {
  const fs::path t = fs::absolute(target).lexically_normal();
  const bool named = t.has_filename();
  return {named ? t.parent_path() : t.parent_path().parent_path(),
          fmt::format(".{}.partial-", (named ? t.filename() : t.parent_path().filename()).string())};
}

}  // namespace

void remove_stale_partials(const std::string& target) {
  const auto [parent, prefix] = partial_place(target);
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string entry = it->path().filename().string();
    if (entry.rfind(prefix, 0) != 0) continue;
    // .NAME.partial-PID-N: left by a process that no longer runs (killed before it could clean up)
    const std::string rest = entry.substr(prefix.size());
    const size_t dash = rest.find('-');
    if (dash == std::string::npos || dash == 0 || rest.find_first_not_of("0123456789") != dash) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(rest.substr(0, dash)));
    if (pid == getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code removed;
    fs::remove_all(it->path(), removed);
  }
}

std::string partial_path(const std::string& target) {
  remove_stale_partials(target);
  static std::atomic<int> counter{0};
  const auto [parent, prefix] = partial_place(target);
  return (parent / fmt::format("{}{}-{}", prefix, getpid(), counter++)).string();
}

StagedFolder::StagedFolder(std::string target) : target_(std::move(target)) {
  std::error_code ec;
  if (read_only_folder(target_)) fail("{}: is a read-only folder; foveal does not write into a read-only folder", target_);
  check_not_read_only(target_);
  staging_ = partial_path(target_);
  fs::create_directories(staging_, ec);
  if (ec) fail("{}: cannot create a folder beside it for the output ({}): {}", target_, staging_, ec.message());
}

StagedFolder::~StagedFolder() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

void StagedFolder::commit() {
  std::error_code ec;
  fs::create_directories(target_, ec);
  if (ec) fail("{}: cannot create the output folder: {}", target_, ec.message());
  for (const auto& e : fs::directory_iterator(staging_)) check_not_read_only((fs::path(target_) / e.path().filename()).string());
  for (const auto& e : fs::directory_iterator(staging_)) {
    fs::rename(e.path(), fs::path(target_) / e.path().filename(), ec);
    if (ec) fail("{}: cannot move {} into it: {}", target_, e.path().filename().string(), ec.message());
  }
  fs::remove(staging_, ec);
  committed_ = true;
}

}  // namespace foveal
