// apps/perceive_command.cpp — `foveal perceive`: a person's eye applied to the researcher's own
// stimuli (an image, a folder of images or a video), gaze-contingent: the optics (defocus at the
// viewing distance or a depth map), then the ocular media, the retina and colour vision.
#include "commands.h"
#include "foveal/gaze/recording.h"
#include "foveal/gaze/steps.h"
#include "foveal/impair/field_picture.h"
#include "foveal/impair/profile.h"
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/timer.h"
#include "foveal/experiments/perceive.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace foveal::app {

namespace {

// The command's options as typed.
struct PerceiveOptions {
  std::string input, output, eye = "healthy", gaze, depth, display = "47.5,30,60", stimulus, amsler, field_map;
  double fps = 30, start = 0;
  std::optional<double> pupil;  // not given: the eye's (a profile's pupil_mm, else 3.5)
  int threads = 0, taps = 64;
  bool no_optics = false, quiet = false;
  GazeOptions gaze_options;
};

// The eye, the display and the depth map, from the options.
Perceiver make_perceiver(const PerceiveOptions& o) {
  PerceiveParams p;
  p.eye = resolve_eye(o.eye, {o.pupil, std::nullopt});
  p.optics = !o.no_optics;
  p.blur.taps = o.taps;
  p.display = parse_display(o.display);
  if (std::count(o.display.begin(), o.display.end(), ',') == 2) p.display.res_x = p.display.res_y = 0;  // the input's size
  if (!(o.start >= 0 && std::isfinite(o.start))) fail("--start: must be a finite number of seconds >= 0, got {}", o.start);
  if (!o.depth.empty()) {
    p.depth = load_image(o.depth);
    check_depth_map(*p.depth, o.depth);
  }
  return Perceiver(std::move(p));
}

// The gaze: a point, or a recording's fixation at each frame's time.
FrameGaze open_gaze(const PerceiveOptions& o, const PerceiveInput& in) {
  // A point is X,Y (numbers, or anything else with one comma that is no file: "nan,nan" is a bad
  // point, not a recording's name); the rest names a recording
  std::error_code ec;
  const bool point_like = std::count(o.gaze.begin(), o.gaze.end(), ',') == 1 && !std::filesystem::exists(o.gaze, ec);
  if (o.gaze.empty()) return FrameGaze();
  if (point_like) return FrameGaze(parse_vec2("--gaze", o.gaze));
  if (o.gaze.find("://") != std::string::npos)
    fail("--gaze: a live tracker drives the real-time commands (foveal view, simulate); perceive takes a point or a recording");
  if (!in.folder && !in.video)
    fail("--gaze {}: a recording's gaze needs a video or a folder of frames (one fixation per frame's time); for one image give --gaze X,Y",
         o.gaze);
  const Display screen = parse_display(o.display, Display{});
  const Recording recording = read_recording_warned(o.gaze, resolve_read_options(o.gaze_options, screen));
  return FrameGaze(recording, screen, parse_step_fixations(o.gaze_options.fixation), resolve_fixation_params(o.gaze_options), o.start,
                   o.stimulus);
}

void print_perceive(const PerceiveOptions& o, const Perceiver& p, const PerceiveInput& in, double frame_ms) {
  const size_t frames = in.amsler ? 1 : in.frames.size();
  const EyeSpec& eye = p.params().eye;
  fmt::print("foveal perceive: {} ({} frame{}{}), eye {}\n", o.input, frames, frames == 1 ? "" : "s",
             in.video ? fmt::format(" at {:.3g} fps", in.fps) : "", eye.source);
  const FocusRange range = focus_range(eye.eye);
  auto point = [](double m) { return m < 1e9 ? fmt::format("{:.2f} m", m) : std::string("infinity"); };
  fmt::print("  optics   {}\n", p.params().optics
                                    ? fmt::format("focus {} … {}, pupil {} mm, viewing distance {} cm{}", point(range.near_point_m()),
                                                  point(range.far_point_m()), eye.eye.pupil_diameter_mm, p.params().display.distance_cm,
                                                  p.params().depth ? ", depth map" : "")
                                    : std::string("off"));
  fmt::print("  impaired {}\n", eye.impair.describe());
  if (!in.amsler) fmt::print("  time     {:.1f} ms per frame\n", frame_ms / in.frames.size());
  fmt::print("  wrote    {}{}{}\n", o.output, o.amsler.empty() ? "" : ", " + o.amsler, o.field_map.empty() ? "" : ", " + o.field_map);
}

int run_perceive(const PerceiveOptions& o) {
  resolve_fixation_params(o.gaze_options);  // the fixation filter's options are checked without --gaze too
  const ThreadScope threads(o.threads);
  const Perceiver p = make_perceiver(o);
  const PerceiveInput in = open_perceive_input(o.input, o.output, o.fps, "-o");
  if (in.amsler && !o.gaze.empty()) fail("--gaze: the Amsler grid is always fixated at its centre");
  const FrameGaze gaze = open_gaze(o, in);
  // Progress on a terminal once a run takes over a second
  const bool show = !o.quiet && isatty(fileno(stderr));
  const Timer clock;
  const double frame_ms = perceive_files(p, in, gaze, o.output, [&](size_t done, size_t total) {
    if (show && clock.ms() > 1000) fmt::print(stderr, "\r  frame {}/{} ", done, total);
  });
  if (show && clock.ms() > 1000) fmt::print(stderr, "\r{:40}\r", "");
  // The pictures of the eye last, once the frames are written: a run that fails writes neither (an
  // Amsler grid named like a missing input was written first, and then read as the input)
  if (!o.amsler.empty()) save_image(amsler_grid(p.passes(), 20), o.amsler);
  if (!o.field_map.empty()) write_field_picture(p.params().eye.impair.field, p.passes().field_map(), o.field_map);
  if (!o.quiet) print_perceive(o, p, in, frame_ms);
  return 0;
}

}  // namespace

std::function<int()> add_perceive_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("perceive",
                                 "a person's eye applied to your own stimuli: an image, a folder of images or a video, "
                                 "gaze-contingent (optics, media, visual field, colour vision)");

  auto o = std::make_shared<PerceiveOptions>();
  cmd->add_option("input", o->input,
                  "a PNG/JPEG/EXR/PFM image, a folder of images, a video (ffmpeg), builtin:amsler (an Amsler grid) or builtin:lamps "
                  "(a glare test card: bright lamps in a dark room, linear HDR)")
      ->required();
  cmd->add_option("-o,--output", o->output, "the same kind as the input: an image file, a folder, a video file")
      ->required()
      ->check(an_output());
  cmd->add_option("--eye", o->eye,
                  "the eye: presets joined with '+' (as for simulate: cataract:0.5, cvd:deutan:0.6, field:arcuate:20, "
                  "field:24-2:FILE.csv, amd:5, myopia:-2, …) or a profile .json")
      ->capture_default_str();
  cmd->add_option("--gaze", o->gaze,
                  "X,Y in image pixels (default: the centre), or a recording (EyeLink .asc, Pupil, Tobii, t,x,y CSV): "
                  "each frame fixates where the recording's fixation was at the frame's time");
  cmd->add_option("--depth", o->depth,
                  "per-pixel distance from the eye in metres (EXR/PFM, the input's size); without it the stimulus is "
                  "a plane at the viewing distance");
  cmd->add_option("--display", o->display,
                  "W_CM,H_CM,DIST_CM[,RES_X,RES_Y]: the screen the stimulus fills and the viewing distance "
                  "(without a resolution: the stimulus fills the width with square pixels)")
      ->capture_default_str();
  cmd->add_option("--stimulus", o->stimulus, "X,Y,W,H: where the stimulus was shown on the recording's screen (default: the whole screen)");
  cmd->add_option("--fps", o->fps, "frame rate of a folder of frames (a video's own rate is used)")->capture_default_str();
  cmd->add_option("--start", o->start, "the recording's time, s from its first sample, at the first frame")->capture_default_str();
  cmd->add_option("--pupil", o->pupil, "pupil diameter, mm (overrides a profile's pupil_mm; default: the profile's, else 3.5)");
  cmd->add_option("--blur-taps", o->taps, "most blur taps per pixel")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_flag("--no-optics", o->no_optics, "skip the defocus blur (the media, field and colour only)");
  cmd->add_option("--amsler", o->amsler, "also write the Amsler grid as this eye sees it (PNG)")->check(output_file(image_extensions()));
  cmd->add_option("--field-map", o->field_map, "also write the visual field's loss map, ±30°, with the test locations (PNG)")
      ->check(output_file());
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");
  o->gaze_options.fixation = "auto";  // the field moves from fixation to fixation
  add_gaze_options(*cmd, o->gaze_options,
                   "where the fixations come from: auto (= nhr, the recommended event detector; pursuit a step every 100 ms), nhp, ivt "
                   "(velocity threshold), "
                   "idt (dispersion threshold) or tracker (the recording's own fixation events)");

  return [o] { return run_perceive(*o); };
}

}  // namespace foveal::app
