// tests/cli_helpers.h — run the `foveal` executable as a user would and capture what it says.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace foveal_test {

namespace fs = std::filesystem;

struct CliRun {
  int status = -1;
  std::string out, err;
};

// This test process's scratch folder: made the first time it is asked for, removed with what it
// holds when the process exits (ctest runs each test in a process of its own).
class ScratchFolder {
 public:
  ScratchFolder() : path_(fs::temp_directory_path() / ("foveal_cli_" + std::to_string(::getpid()))) { fs::create_directories(path_); }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};
inline const fs::path& scratch_folder() {
  static const ScratchFolder folder;
  return folder.path();
}

// Run the executable with arguments in the scratch folder, behind an optional launcher (env,
// xvfb-run, …); capture exit status and both streams.
inline CliRun run_foveal(const std::string& launcher, const std::string& args) {
  const fs::path& dir = scratch_folder();
  const std::string cmd = "cd '" + dir.string() + "' && " + launcher + " '" FOVEAL_EXE "' " + args + " > out.txt 2> err.txt";
  CliRun r;
  const int raw = std::system(cmd.c_str());
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  auto slurp = [&](const char* name) {
    std::stringstream s;
    s << std::ifstream(dir / name).rdbuf();
    return s.str();
  };
  r.out = slurp("out.txt");
  r.err = slurp("err.txt");
  return r;
}
inline CliRun foveal(const std::string& args) { return run_foveal("", args); }

// A path in this test process's scratch folder.
inline fs::path scratch(const std::string& name) { return scratch_folder() / name; }

inline size_t lines(const std::string& s) {
  size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// Bad input: `foveal ARGS` exits with 1 and says `expected` in one line.
inline void expect_one_line_error(const std::string& args, const std::string& expected) {
  const CliRun r = foveal(args);
  EXPECT_EQ(r.status, 1) << args;
  EXPECT_EQ(lines(r.err), 1u) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
}

// A 500 Hz t,x,y,confidence recording on a 480×300 screen: 300 ms fixations at (100, 100),
// (400, 200) and (240, 150), joined by 28 ms saccades — or, with `blink_before_third`, the
// second and third by a 150 ms blink (confidence 0) instead. Returns its path.
inline std::string write_three_fixations(const std::string& name, bool blink_before_third = false) {
  const fs::path path = scratch(name);
  fs::create_directories(path.parent_path());
  std::ofstream out(path);
  out << "t,x,y,confidence\n";
  const double points[3][2] = {{100, 100}, {400, 200}, {240, 150}};
  double t = 0;
  for (int f = 0; f < 3; ++f) {
    for (int i = 0; i < 150; ++i, t += 0.002)
      out << t << "," << points[f][0] + 0.3 * std::sin(i) << "," << points[f][1] + 0.3 * std::cos(i) << ",0.9\n";
    if (f == 2) break;
    if (f == 1 && blink_before_third) {
      for (int i = 0; i < 75; ++i, t += 0.002) out << t << ",0,0,0\n";
      continue;
    }
    for (int i = 1; i < 15; ++i, t += 0.002)
      out << t << "," << points[f][0] + (points[f + 1][0] - points[f][0]) * i / 15.0 << ","
          << points[f][1] + (points[f + 1][1] - points[f][1]) * i / 15.0 << ",0.9\n";
  }
  return path.string();
}

}  // namespace foveal_test
