// tests/cli_helpers.h — run the `foveal` executable as a user would and capture what it says.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

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

// Run the executable with arguments in a scratch folder; capture exit status and both streams.
inline CliRun foveal(const std::string& args) {
  static const fs::path dir = fs::temp_directory_path() / ("foveal_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string cmd = "cd '" + dir.string() + "' && '" FOVEAL_EXE "' " + args + " > out.txt 2> err.txt";
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

inline fs::path scratch(const std::string& name) { return fs::temp_directory_path() / ("foveal_cli_" + std::to_string(::getpid())) / name; }

inline size_t lines(const std::string& s) {
  size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace foveal_test
