// foveal/util/files.cpp — never over an input, all or nothing (see files.h).
#include "foveal/util/files.h"

#include "foveal/util/error.h"

#include <atomic>
#include <filesystem>
#include <mutex>
#include <set>
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

struct Guard {
  std::mutex mutex;
  std::set<std::string> inputs;  // resolved paths
  std::atomic<bool> on{false};
};
Guard& guard() {
  static Guard g;
  return g;
}

}  // namespace

void check_output_is_not_input(const std::string& output, const std::string& input, const char* option) {
  if (output.empty() || input.empty()) return;
  if (same_file(output, input)) fail("{} {}: is the input {}; foveal never writes over its inputs", option, output, input);
}

void set_input_guard(bool on) { guard().on = on; }

void note_input(const std::string& path) {
  Guard& g = guard();
  if (!g.on) return;
  const std::string r = resolved(path);
  const std::lock_guard lock(g.mutex);
  g.inputs.insert(r);
}

void check_not_an_input(const std::string& output) {
  Guard& g = guard();
  if (!g.on) return;
  const std::string r = resolved(output);
  const std::lock_guard lock(g.mutex);
  for (const std::string& in : g.inputs)
    if (in == r || same_file(in, output)) fail("{}: is an input of this run; foveal never writes over its inputs", output);
}

StagedFolder::StagedFolder(std::string target) : target_(std::move(target)) {
  const fs::path t = fs::absolute(target_).lexically_normal();
  const std::string name = (t.has_filename() ? t.filename() : t.parent_path().filename()).string();
  const fs::path parent = t.has_filename() ? t.parent_path() : t.parent_path().parent_path();
  static std::atomic<int> counter{0};
  staging_ = (parent / fmt::format(".{}.partial-{}-{}", name, getpid(), counter++)).string();
  std::error_code ec;
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
  for (const auto& e : fs::directory_iterator(staging_)) {
    fs::rename(e.path(), fs::path(target_) / e.path().filename(), ec);
    if (ec) fail("{}: cannot move {} into it: {}", target_, e.path().filename().string(), ec.message());
  }
  fs::remove(staging_, ec);
  committed_ = true;
}

}  // namespace foveal
