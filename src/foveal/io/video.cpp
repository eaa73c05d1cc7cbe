// foveal/io/video.cpp — runs ffmpeg as a child process (no shell), its messages to a log file.
#include "foveal/io/video.h"

#include "foveal/util/text.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <fmt/format.h>

#include <cctype>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

extern char** environ;

namespace foveal {

namespace {

// Run a program (no shell) with its output to `stdout_path` (or /dev/null) and its messages to a
// log; throws Error naming `what` with the program's last message when it fails.
void run_program(std::vector<std::string> args, const std::string& what, const std::string& stdout_path = "/dev/null") {
  namespace fs = std::filesystem;
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string log = (fs::temp_directory_path() / fmt::format("foveal-{}-{}.log", args[0], getpid())).string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0].c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) fail("{}: cannot run {} ({}); install it (apt-get install ffmpeg)", what, args[0], std::strerror(spawned));
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) fail("{}: lost the {} process", what, args[0]);
  std::string message;
  if (fs::exists(log)) {
    message = text::read_file(log);
    fs::remove(log);
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
    const auto last_line = message.rfind('\n');
    fail("{}: {} failed{}{}", what, args[0], message.empty() ? "" : ": ",
         last_line == std::string::npos ? message : message.substr(last_line + 1));
  }
}

}  // namespace

void encode_video(const std::string& pattern, double fps, const std::string& output) {
  namespace fs = std::filesystem;
  check_not_an_input(output);
  const std::string ext = fs::path(output).extension().string();
  std::vector<std::string> args{"ffmpeg", "-y", "-nostdin", "-loglevel", "error", "-framerate", fmt::format("{}", fps), "-start_number",
                                "0", "-i", pattern,
                                // even sizes for 4:2:0 chroma
                                "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"};
  if (ext == ".mp4" || ext == ".mkv" || ext == ".mov")
    args.insert(args.end(), {"-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"});
  else if (ext == ".webm")
    args.insert(args.end(), {"-c:v", "libvpx-vp9", "-pix_fmt", "yuv420p", "-b:v", "0", "-crf", "30"});
  args.push_back(output);
  run_program(args, output + " (the frames are kept)");
}

double decode_video(const std::string& input, const std::string& frame_pattern) {
  namespace fs = std::filesystem;
  if (!fs::is_regular_file(input)) fail("{}: no such video file", input);
  note_input(input);
  // the frame rate, as ffprobe states it ("30000/1001")
  const std::string rate_file = (fs::temp_directory_path() / fmt::format("foveal-rate-{}.txt", getpid())).string();
  struct Remove {  // however ffprobe ends, the file goes
    std::string path;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  } remove{rate_file};
  run_program({"ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries", "stream=avg_frame_rate", "-of",
               "default=noprint_wrappers=1:nokey=1", input},
              input, rate_file);
  std::string rate = text::read_file(rate_file);
  while (!rate.empty() && std::isspace(static_cast<unsigned char>(rate.back()))) rate.pop_back();
  double num = 0, den = 1;
  if (std::sscanf(rate.c_str(), "%lf/%lf", &num, &den) < 1 || !(num > 0) || !(den > 0))
    fail("{}: no video stream with a frame rate (ffprobe said '{}')", input, rate);
  run_program({"ffmpeg", "-y", "-nostdin", "-loglevel", "error", "-i", input, "-vsync", "0", "-start_number", "0", frame_pattern}, input);
  return num / den;
}

}  // namespace foveal
