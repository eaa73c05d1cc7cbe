// foveal/io/video.cpp — runs ffmpeg as a child process (no shell), its messages to a log file.
#include "foveal/io/video.h"

#include "foveal/gaze/text.h"
#include "foveal/util/error.h"

#include <fmt/format.h>

#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

extern char** environ;

namespace foveal {

void encode_video(const std::string& pattern, double fps, const std::string& output) {
  namespace fs = std::filesystem;
  const std::string ext = fs::path(output).extension().string();
  std::vector<std::string> args{"ffmpeg", "-y", "-nostdin", "-loglevel", "error", "-framerate", fmt::format("{}", fps),
                                "-start_number", "0", "-i", pattern,
                                // even sizes for 4:2:0 chroma
                                "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"};
  if (ext == ".mp4" || ext == ".mkv" || ext == ".mov") args.insert(args.end(), {"-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"});
  else if (ext == ".webm") args.insert(args.end(), {"-c:v", "libvpx-vp9", "-pix_fmt", "yuv420p", "-b:v", "0", "-crf", "30"});
  args.push_back(output);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  const std::string log = (fs::temp_directory_path() / fmt::format("foveal-ffmpeg-{}.log", getpid())).string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "ffmpeg", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) fail("{}: cannot run ffmpeg ({}); install it (apt-get install ffmpeg) — the frames are kept", output, std::strerror(spawned));
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) fail("{}: lost the ffmpeg process", output);
  std::string message;
  if (fs::exists(log)) {
    message = text::read_file(log);
    fs::remove(log);
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
    const auto last_line = message.rfind('\n');
    fail("{}: ffmpeg failed{}{}", output, message.empty() ? "" : ": ",
         last_line == std::string::npos ? message : message.substr(last_line + 1));
  }
}

}  // namespace foveal
