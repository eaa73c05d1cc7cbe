// foveal/experiments/perceive.h — the perceive driver: a stimulus (an image, a folder of images, a
// video, a built-in card) seen frame by frame through a Perceiver (vision/perceive.h), each frame
// at its gaze (a point, or a recording's fixation at the frame's time), written as the input was.
// `foveal perceive` and foveal.perceive run this same code.
#pragma once

#include "foveal/gaze/recording.h"
#include "foveal/gaze/steps.h"
#include "foveal/vision/perceive.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

// The frames of an input: one image, a folder's images (sorted by name), a video's frames
// (decoded by ffmpeg into a temporary folder removed with this object), or builtin:lamps /
// builtin:amsler.
struct PerceiveInput {
  std::vector<std::filesystem::path> frames;
  std::shared_ptr<const std::string> decoded;  // a video's temporary folder (removed with the last copy)
  double fps = 30;                             // a video's own rate, else the rate given
  bool amsler = false, lamps = false, folder = false, video = false;
  std::string frame_dir() const { return decoded ? *decoded : std::string(); }
};
// `output` (empty: none, the frames are only read) must be of the input's kind and not the input;
// errors name the input, and the output as `output_name` (the front end's word for it).
PerceiveInput open_perceive_input(const std::string& input, const std::string& output, double fps, const char* output_name = "output");

// Frame k's stimulus in linear RGB(A): PNG/JPEG/BMP/TIFF sRGB-decoded, EXR/PFM as stored.
Image load_stimulus(const PerceiveInput& in, size_t k);
bool is_float_image_path(const std::string& path);

// Each frame's gaze: a fixed point, or the fixation under way at the frame's time in a recording.
class FrameGaze {
 public:
  FrameGaze() = default;  // the image's centre
  explicit FrameGaze(glm::dvec2 point) : fixed_(point) {}
  // A recording's fixations (by `source`, as simulate's steps) on the screen `screen` (its physical
  // size for the angles); `start_s` the recording's time (from its first sample) at the first
  // frame; `stimulus` X,Y,W,H where the stimulus was on the recording's screen (empty: all of it).
  FrameGaze(const Recording& recording, const Display& screen, StepFixations source, const FixationParams& params, double start_s,
            const std::string& stimulus);
  // Frame k's gaze in a w × h image at `fps`: the fixation under way at its time (the last begun;
  // the centre before the first), or the fixed point, or the centre.
  glm::dvec2 at(size_t k, double fps, int w, int h) const;
  bool from_recording() const { return !fixations_.empty(); }
  size_t fixations() const { return fixations_.size(); }

 private:
  std::optional<glm::dvec2> fixed_;
  std::vector<GazeStep> fixations_;
  std::optional<ScreenMapping> mapping_;
  double t0_ = 0;
};

// Every frame seen and written to `output` (a folder's all at once when all are seen; a video's
// through ffmpeg at the input's rate); `progress` is told each frame done. Returns ms of seeing.
double perceive_files(const Perceiver& perceiver, const PerceiveInput& in, const FrameGaze& gaze, const std::string& output,
                      const std::function<void(size_t done, size_t total)>& progress = {});

// Every frame seen, kept in memory (linear float; the input's channels, grey made RGB).
std::vector<Image> perceive_frames(const Perceiver& perceiver, const PerceiveInput& in, const FrameGaze& gaze);

}  // namespace foveal
