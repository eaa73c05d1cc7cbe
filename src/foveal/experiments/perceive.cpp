// foveal/experiments/perceive.cpp — the perceive driver over files.
#include "foveal/experiments/perceive.h"

#include "foveal/io/image_io.h"
#include "foveal/io/video.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <fmt/core.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cctype>
#include <unistd.h>

namespace foveal {

namespace fs = std::filesystem;

namespace {

bool is_image(const fs::path& p) {
  const std::string ext = lower_extension(p.string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" || ext == ".tiff" || ext == ".exr" ||
         ext == ".pfm";
}

bool is_video(const fs::path& p) {
  const std::string ext = lower_extension(p.string());
  return ext == ".mp4" || ext == ".mkv" || ext == ".mov" || ext == ".webm" || ext == ".avi" || ext == ".m4v";
}

// A temporary folder for a video's frames, unique per call (threads and processes), removed with
// everything in it when the last copy of its handle goes.
std::shared_ptr<const std::string> temporary_folder() {
  static std::atomic<unsigned> counter{0};
  auto* path = new std::string((fs::temp_directory_path() / fmt::format("foveal-perceive-{}-{}", getpid(), counter++)).string());
  fs::create_directories(*path);
  return std::shared_ptr<const std::string>(path, [](const std::string* p) {
    std::error_code ec;
    fs::remove_all(*p, ec);
    delete p;
  });
}

}  // namespace

bool is_float_image_path(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".exr" || ext == ".pfm";
}

PerceiveInput open_perceive_input(const std::string& input, const std::string& output, double fps, const char* output_name) {
  if (!(fps > 0 && std::isfinite(fps))) fail("fps: must be positive, got {}", fps);
  PerceiveInput in;
  in.fps = fps;
  in.amsler = input == "builtin:amsler";
  in.lamps = input == "builtin:lamps";
  in.folder = !in.amsler && !in.lamps && fs::is_directory(input);
  in.video = !in.amsler && !in.lamps && !in.folder && is_video(input);
  if (!output.empty()) {
    check_output_is_not_input(output, input, output_name);
    if (in.folder && fs::exists(output) && !fs::is_directory(output))
      fail("{} {}: a folder of images needs a folder as output", output_name, output);
    if (in.folder && (is_video(output) || is_image(output)))
      fail("{} {}: a folder of images is written as a folder of images (one per input); give a folder name", output_name, output);
    if (in.video && !is_video(output)) fail("{} {}: a video needs a video file as output (.mp4, .mkv, .mov, .webm)", output_name, output);
  }
  if (in.amsler) return in;
  if (in.folder) {
    for (const auto& e : fs::directory_iterator(input))
      if (e.is_regular_file() && is_image(e.path())) in.frames.push_back(e.path());
    std::sort(in.frames.begin(), in.frames.end());
    if (in.frames.empty()) fail("{}: no images (PNG, JPEG, BMP, TIFF, EXR, PFM) in the folder", input);
  } else if (in.video) {
    in.decoded = temporary_folder();
    in.fps = decode_video(input, *in.decoded + "/in_%06d.png");
    for (const auto& e : fs::directory_iterator(*in.decoded)) in.frames.push_back(e.path());
    std::sort(in.frames.begin(), in.frames.end());
    if (in.frames.empty()) fail("{}: the video has no frames", input);
  } else if (in.lamps) {
    in.frames.push_back("builtin:lamps");
  } else {
    if (!fs::is_regular_file(input)) fail("{}: no such image, folder or video", input);
    if (!is_image(input)) fail("{}: not an image perceive reads (PNG, JPEG, BMP, TIFF, EXR, PFM), a folder or a video", input);
    in.frames.push_back(input);
  }
  return in;
}

Image load_stimulus(const PerceiveInput& in, size_t k) {
  if (in.lamps) return lamps_card();
  const std::string path = in.frames.at(k).string();
  return stimulus_to_linear(load_image(path, true), !is_float_image_path(path), path);
}

namespace {

// Frame k as the eye sees it, at its gaze.
Image see_frame(const Perceiver& perceiver, const PerceiveInput& in, const FrameGaze& gaze, size_t k) {
  const Image image = load_stimulus(in, k);
  return perceiver.see(image, gaze.at(k, in.fps, image.width, image.height));
}

}  // namespace

FrameGaze::FrameGaze(const Recording& recording, const Display& screen, StepFixations source, const FixationParams& params, double start_s,
                     const std::string& stimulus) {
  if (recording.samples.empty()) fail("{}: no samples", recording.source);
  if (!(start_s >= 0 && std::isfinite(start_s))) fail("start_s: must be a finite number of seconds >= 0, got {}", start_s);
  const double length = recording.samples.back().t_s - recording.samples.front().t_s;
  if (start_s > length) fail("start_s: {}: the recording {} lasts {:.3f} s", start_s, recording.source, length);
  const GazeGeometry geometry(screen, recording.screen_px);
  fixations_ = recording_steps(recording, geometry, source, params);
  if (fixations_.empty()) fail("{}: no fixations", recording.source);
  std::stable_sort(fixations_.begin(), fixations_.end(), [](const GazeStep& a, const GazeStep& b) { return a.start_s < b.start_s; });
  t0_ = recording.samples.front().t_s + start_s;
  mapping_ = make_screen_mapping(recording.screen_px, {0, 0}, stimulus);
}

glm::dvec2 FrameGaze::at(size_t k, double fps, int w, int h) const {
  const double time = t0_ + k / fps;
  // The last fixation begun by then (the steps are in time order)
  const auto next = std::upper_bound(fixations_.begin(), fixations_.end(), time, [](double t, const GazeStep& g) { return t < g.start_s; });
  if (next == fixations_.begin()) return fixed_.value_or(glm::dvec2(w / 2.0, h / 2.0));
  ScreenMapping m = *mapping_;
  m.render_px = {w, h};
  return m.to_render(std::prev(next)->screen_px);
}

double perceive_files(const Perceiver& perceiver, const PerceiveInput& in, const FrameGaze& gaze, const std::string& output,
                      const std::function<void(size_t, size_t)>& progress) {
  if (in.amsler) {
    save_image(amsler_grid(perceiver.passes(), 20), output);
    return 0;
  }
  // A folder's frames go into a staging folder beside the output, moved into place when every
  // frame is seen: one corrupt image leaves no half-written folder
  std::optional<StagedFolder> staged;
  if (in.folder) staged.emplace(output);
  const fs::path out_dir = in.folder ? fs::path(staged->path()) : in.video ? fs::path(in.frame_dir()) : fs::path();
  double frame_ms = 0;
  for (size_t k = 0; k < in.frames.size(); ++k) {
    const auto started = std::chrono::steady_clock::now();
    const Image seen = see_frame(perceiver, in, gaze, k);
    std::string target;
    if (in.folder)
      target = (out_dir / in.frames[k].filename()).string();
    else if (in.video)
      target = (out_dir / fmt::format("out_{:06d}.png", k)).string();
    else
      target = output;
    save_image(seen, target, !is_float_image_path(target));
    frame_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
    if (progress) progress(k + 1, in.frames.size());
  }
  if (in.video) encode_video((fs::path(in.frame_dir()) / "out_%06d.png").string(), in.fps, output);
  if (staged) staged->commit();
  return frame_ms;
}

std::vector<Image> perceive_frames(const Perceiver& perceiver, const PerceiveInput& in, const FrameGaze& gaze) {
  std::vector<Image> out;
  if (in.amsler) {
    out.push_back(amsler_grid(perceiver.passes(), 20));
    return out;
  }
  for (size_t k = 0; k < in.frames.size(); ++k) out.push_back(see_frame(perceiver, in, gaze, k));
  return out;
}

}  // namespace foveal
