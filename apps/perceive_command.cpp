// apps/perceive_command.cpp — `foveal perceive`: a person's eye applied to the researcher's own
// stimuli (an image, a folder of images or a video), gaze-contingent: the optics (defocus at the
// viewing distance or a depth map), then the ocular media, the retina and colour vision.
#include "commands.h"
#include "foveal/gaze/recording.h"
#include "foveal/gaze/steps.h"
#include "foveal/impair/field_picture.h"
#include "foveal/impair/profile.h"
#include "foveal/io/image_io.h"
#include "foveal/io/video.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/gaze_point.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/timer.h"
#include "foveal/vision/blur.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numbers>
#include <unistd.h>

namespace foveal::app {

namespace {

namespace fs = std::filesystem;

bool is_float_format(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".exr" || ext == ".pfm" || ext == ".EXR" || ext == ".PFM";
}

bool is_image(const fs::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" || ext == ".tiff" || ext == ".exr" ||
         ext == ".pfm";
}

bool is_video(const fs::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".mp4" || ext == ".mkv" || ext == ".mov" || ext == ".webm" || ext == ".avi" || ext == ".m4v";
}

float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }

// An input frame as linear RGB: 8/16-bit files are sRGB-decoded, EXR/PFM kept as stored
Image load_linear(const std::string& path) {
  Image im = load_image(path, true);
  if (im.channels == 1) {  // grey: three equal channels
    Image rgb(im.width, im.height, 3);
    for (size_t i = 0; i < im.pixels.size(); ++i) rgb.pixels[i * 3] = rgb.pixels[i * 3 + 1] = rgb.pixels[i * 3 + 2] = im.pixels[i];
    im = std::move(rgb);
  }
  if (im.channels != 3 && im.channels != 4) fail("{}: {} channels; perceive reads grey, RGB or RGBA images", path, im.channels);
  if (!is_float_format(path))
    for (size_t i = 0; i < im.pixels.size(); ++i)
      if (im.channels == 3 || i % 4 != 3) im.pixels[i] = srgb_to_linear(im.pixels[i]);  // alpha is no colour
  return im;
}

// A glare test card, linear HDR: a dark room (0.02) with bright lamps (luminance 40) and a white
// bar chart, 960×540 — what forward scatter shows best
Image lamps_card() {
  Image im(960, 540, 3, 0.02f);
  const glm::vec2 lamps[] = {{160, 140}, {480, 110}, {800, 140}, {300, 420}, {660, 420}};
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      float v = 0.02f;
      for (const glm::vec2 c : lamps)
        if (glm::length(glm::vec2(x, y) - c) < 9) v = 40.0f;
      if (y > 250 && y < 300 && x > 280 && x < 680 && (x / 20) % 2 == 0) v = 0.8f;  // bars of a chart
      for (int k = 0; k < 3; ++k) im.at(x, y, k) = v;
    }
  return im;
}

struct Perceiver {
  EyeSpec eye;
  Display display;
  std::optional<Image> depth;  // metres from the eye, per pixel
  bool optics = true;
  BlurParams blur;
  std::unique_ptr<ImpairmentPasses> passes;

  // One frame seen while fixating `gaze` (image pixels)
  // An RGBA frame: the eye sees its colour, the alpha passes through unchanged (transparent stays
  // transparent: issue 36's finding 4)
  Image see(const Image& in, glm::dvec2 gaze) const {
    if (in.channels == 4) {
      Image rgb(in.width, in.height, 3);
      const size_t n = size_t(in.width) * in.height;
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) rgb.pixels[i * 3 + c] = in.pixels[i * 4 + c];
      const Image seen = see_rgb(rgb, gaze);
      Image out = in;
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) out.pixels[i * 4 + c] = seen.pixels[i * 3 + c];
      return out;
    }
    return see_rgb(in, gaze);
  }

  Image see_rgb(const Image& in, glm::dvec2 gaze) const {
    if (depth && (depth->width != in.width || depth->height != in.height))
      fail("--depth: {}x{}, the input is {}x{}", depth->width, depth->height, in.width, in.height);
    check_gaze_point("--gaze", gaze.x, gaze.y, in.width, in.height);
    const Display d = resolve_display_for(in);
    const Retinotopy r = display_retinotopy(d, in.width, in.height, gaze);
    Image out = in;
    if (optics) {
      // The eye accommodates to the fixated point; a pixel's CoC is A·|1/D − v| plus the peripheral
      // penalty × its eccentricity (as simulate; without depth the stimulus is a plane at the viewing distance)
      const double plane_m = d.distance_cm / 100.0;
      auto depth_at = [&](double x, double y) {  // clamped in floating point: a far gaze is no int overflow
        if (!depth) return plane_m;
        const int xi = static_cast<int>(std::clamp(x, 0.0, in.width - 1.0)), yi = static_cast<int>(std::clamp(y, 0.0, in.height - 1.0));
        return static_cast<double>(depth->at(xi, yi, 0));  // finite and > 0, or +inf (far): checked when loaded
      };
      const double v = accommodate(eye.eye, depth_at(gaze.x, gaze.y));
      const double penalty = peripheral_penalty_per_deg(eye.eye);
      std::vector<float> coc(size_t(in.width) * in.height);
      CocShape shape;
      const bool astigmatic = eye.eye.cylinder_d > 0;
      if (astigmatic) shape.scale.resize(coc.size());
      shape.axis_deg = static_cast<float>(eye.eye.cylinder_axis_deg);
      for (int y = 0; y < in.height; ++y)
        for (int x = 0; x < in.width; ++x) {
          const size_t i = size_t(y) * in.width + x;
          const double ecc = glm::length(glm::dvec2(r.field_deg[i]));
          const glm::dvec2 axes = glm::degrees(coc_axes_rad(eye.eye, depth_at(x, y), v)) + penalty * ecc;
          const double major = std::max(axes.x, axes.y);
          coc[i] = static_cast<float>(major * r.ppd);
          if (astigmatic) shape.scale[i] = major > 0 ? glm::vec2(axes / major) : glm::vec2(1.0f);
        }
      out = variable_blur(in, coc, blur, astigmatic ? &shape : nullptr);
    }
    if (passes) passes->apply(out, r);
    return out;
  }

  Display resolve_display_for(const Image& in) const {
    Display d = display;
    if (d.res_x <= 0 || d.res_y <= 0) {  // the stimulus fills the display's width, with square pixels
      d.res_x = in.width;
      d.res_y = in.height;
      d.height_cm = d.width_cm * in.height / in.width;
    }
    return d;
  }
};

}  // namespace

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

// A depth map: metres from the eye per pixel, each finite and > 0 or +inf (far away). NaN, zero or
// negative depths are refused with their count and the first one's pixel (they were silently taken
// for infinitely far: issue 36's finding 13).
Image load_depth(const std::string& path) {
  Image d = load_image(path);
  size_t bad = 0;
  glm::ivec2 first(-1);
  for (int y = 0; y < d.height; ++y)
    for (int x = 0; x < d.width; ++x) {
      const float v = d.at(x, y, 0);
      if (!(v > 0)) {  // NaN, zero, negative (+inf passes: far)
        if (bad++ == 0) first = {x, y};
      }
    }
  if (bad)
    fail("{}: {} depths are NaN, zero or negative (the first at pixel {},{}: {}); depths are metres from the eye, > 0, or inf for far away",
         path, bad, first.x, first.y, d.at(first.x, first.y, 0));
  return d;
}

// The eye, the display and the passes, from the options.
Perceiver make_perceiver(const PerceiveOptions& o) {
  Perceiver p;
  p.eye = resolve_eye(o.eye, {o.pupil, std::nullopt});
  p.optics = !o.no_optics;
  p.blur.taps = o.taps;
  p.display = parse_display(o.display);
  if (std::count(o.display.begin(), o.display.end(), ',') == 2) p.display.res_x = p.display.res_y = 0;  // the input's size
  if (!(o.fps > 0 && std::isfinite(o.fps))) fail("--fps: must be positive, got {}", o.fps);
  if (!(o.start >= 0 && std::isfinite(o.start))) fail("--start: must be a finite number of seconds >= 0, got {}", o.start);
  if (!o.depth.empty()) p.depth = load_depth(o.depth);
  p.passes = std::make_unique<ImpairmentPasses>(p.eye.impair.any() ? p.eye.impair : Impairments{});
  return p;
}

// The frames: one image, a folder, a video's frames, or a built-in card.
// A temporary folder, removed with everything in it when the run ends, failed or not.
struct TemporaryFolder {
  std::string path;
  explicit TemporaryFolder(std::string p) : path(std::move(p)) { fs::create_directories(path); }
  ~TemporaryFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
};

struct PerceiveInput {
  std::vector<fs::path> frames;
  std::unique_ptr<TemporaryFolder> decoded;  // a video's decoded frames and the frames seen
  std::string frame_dir;                     // its path
  double fps = 30;
  bool amsler = false, lamps = false, folder = false, video = false;
};

PerceiveInput open_input(const PerceiveOptions& o) {
  PerceiveInput in;
  in.fps = o.fps;
  in.amsler = o.input == "builtin:amsler";
  in.lamps = o.input == "builtin:lamps";
  in.folder = !in.amsler && fs::is_directory(o.input);
  in.video = !in.amsler && !in.folder && is_video(o.input);
  check_output_is_not_input(o.output, o.input, "-o");
  for (const std::string* extra : {&o.amsler, &o.field_map})
    if (!extra->empty()) check_output_is_not_input(*extra, o.input, extra == &o.amsler ? "--amsler" : "--field-map");
  if (in.folder && fs::exists(o.output) && !fs::is_directory(o.output))
    fail("-o {}: a folder of images needs a folder as output", o.output);
  if (in.folder && (is_video(o.output) || is_image(o.output)))
    fail("-o {}: a folder of images is written as a folder of images (one per input); give a folder name", o.output);
  if (in.video && !is_video(o.output)) fail("-o {}: a video needs a video file as output (.mp4, .mkv, .mov, .webm)", o.output);
  if (in.amsler) {
    if (!o.gaze.empty()) fail("--gaze: the Amsler grid is always fixated at its centre");
  } else if (in.folder) {
    for (const auto& e : fs::directory_iterator(o.input))
      if (e.is_regular_file() && is_image(e.path())) in.frames.push_back(e.path());
    std::sort(in.frames.begin(), in.frames.end());
    if (in.frames.empty()) fail("{}: no images (PNG, JPEG, BMP, TIFF, EXR, PFM) in the folder", o.input);
  } else if (in.video) {
    in.decoded = std::make_unique<TemporaryFolder>((fs::temp_directory_path() / fmt::format("foveal-perceive-{}", getpid())).string());
    in.frame_dir = in.decoded->path;
    in.fps = decode_video(o.input, in.frame_dir + "/in_%06d.png");
    for (const auto& e : fs::directory_iterator(in.frame_dir)) in.frames.push_back(e.path());
    std::sort(in.frames.begin(), in.frames.end());
    if (in.frames.empty()) fail("{}: the video has no frames", o.input);
  } else if (in.lamps) {
    in.frames.push_back("builtin:lamps");
  } else {
    if (!fs::is_regular_file(o.input)) fail("{}: no such image, folder or video", o.input);
    if (!is_image(o.input)) fail("{}: not an image perceive reads (PNG, JPEG, BMP, TIFF, EXR, PFM), a folder or a video", o.input);
    in.frames.push_back(o.input);
  }
  return in;
}

// The gaze: a point, or a recording's fixation at each frame's time.
struct PerceiveGaze {
  std::optional<glm::dvec2> fixed;
  std::vector<GazeStep> fixations;
  std::optional<ScreenMapping> mapping;
  double t0 = 0;
  // Frame k's gaze in an image of w × h: the fixation under way at the frame's time (the last one
  // begun; the centre before the first), or the fixed point, or the centre
  glm::dvec2 at(size_t k, double fps, int w, int h) const {
    glm::dvec2 gaze = fixed.value_or(glm::dvec2(w / 2.0, h / 2.0));
    const double time = t0 + k / fps;
    const GazeStep* now = nullptr;
    for (const GazeStep& g : fixations)
      if (g.start_s <= time) now = &g;
    if (now) {
      ScreenMapping m = *mapping;
      m.render_px = {w, h};
      gaze = m.to_render(now->screen_px);
    }
    return gaze;
  }
};

PerceiveGaze open_gaze(const PerceiveOptions& o, const PerceiveInput& in) {
  PerceiveGaze g;
  // A point is X,Y (numbers, or anything else with one comma that is no file: "nan,nan" is a bad
  // point, not a recording's name); the rest names a recording
  std::error_code ec;
  const bool point_like = std::count(o.gaze.begin(), o.gaze.end(), ',') == 1 && !fs::exists(o.gaze, ec);
  const bool recording_gaze = !o.gaze.empty() && !point_like;
  if (!recording_gaze) {
    if (!o.gaze.empty()) g.fixed = parse_vec2("--gaze", o.gaze);
    return g;
  }
  if (o.gaze.find("://") != std::string::npos)
    fail("--gaze: a live tracker drives the real-time commands (foveal view, simulate); perceive takes a point or a recording");
  if (!in.folder && !in.video)
    fail("--gaze {}: a recording's gaze needs a video or a folder of frames (one fixation per frame's time); for one image give --gaze X,Y",
         o.gaze);
  const Display screen = parse_display(o.display, Display{});
  const ReadOptions read = resolve_read_options(o.gaze_options, screen);
  const Recording recording = read_recording_warned(o.gaze, read);
  if (recording.samples.empty()) fail("{}: no samples", recording.source);
  const GazeGeometry geometry(screen, recording.screen_px);
  g.fixations =
      recording_steps(recording, geometry, parse_step_fixations(o.gaze_options.fixation), resolve_fixation_params(o.gaze_options));
  if (g.fixations.empty()) fail("{}: no fixations", recording.source);
  g.t0 = recording.samples.front().t_s + o.start;
  const double length = recording.samples.back().t_s - recording.samples.front().t_s;
  if (o.start > length) fail("--start {}: the recording {} lasts {:.3f} s", o.start, recording.source, length);
  g.mapping = make_screen_mapping(recording.screen_px, {0, 0}, o.stimulus);
  return g;
}

// Every frame seen by the eye and written (a video's through ffmpeg); returns the time, ms.
double see_frames(const PerceiveOptions& o, const Perceiver& p, const PerceiveInput& in, const PerceiveGaze& gaze) {
  // A folder's frames go into a staging folder beside the output, moved into place when every
  // frame is seen: one corrupt image leaves no half-written folder (issue 36's finding 2)
  std::optional<StagedFolder> staged;
  if (in.folder) staged.emplace(o.output);
  const fs::path out_dir = in.folder ? fs::path(staged->path()) : in.video ? fs::path(in.frame_dir) : fs::path();
  const bool show = !o.quiet && isatty(fileno(stderr));
  const Timer clock;
  double frame_ms = 0;
  if (in.amsler) save_image(amsler_grid(*p.passes, 20), o.output);
  for (size_t k = 0; k < in.frames.size(); ++k) {
    const Timer t;
    const Image image = in.lamps ? lamps_card() : load_linear(in.frames[k].string());
    const Image seen = p.see(image, gaze.at(k, in.fps, image.width, image.height));
    std::string target;
    if (in.folder)
      target = (out_dir / in.frames[k].filename()).string();
    else if (in.video)
      target = (out_dir / fmt::format("out_{:06d}.png", k)).string();
    else
      target = o.output;
    save_image(seen, target, !is_float_format(target));
    frame_ms += t.ms();
    if (show && clock.ms() > 1000) fmt::print(stderr, "\r  frame {}/{} ", k + 1, in.frames.size());
  }
  if (show && clock.ms() > 1000) fmt::print(stderr, "\r{:40}\r", "");
  if (in.video) {
    encode_video((fs::path(in.frame_dir) / "out_%06d.png").string(), in.fps, o.output);
  }
  if (staged) staged->commit();
  return frame_ms;
}

void print_perceive(const PerceiveOptions& o, const Perceiver& p, const PerceiveInput& in, double frame_ms) {
  const size_t frames = in.amsler ? 1 : in.frames.size();
  fmt::print("foveal perceive: {} ({} frame{}{}), eye {}\n", o.input, frames, frames == 1 ? "" : "s",
             in.video ? fmt::format(" at {:.3g} fps", in.fps) : "", p.eye.source);
  const FocusRange range = focus_range(p.eye.eye);
  auto point = [](double m) { return m < 1e9 ? fmt::format("{:.2f} m", m) : std::string("infinity"); };
  fmt::print("  optics   {}\n", p.optics ? fmt::format("focus {} … {}, pupil {} mm, viewing distance {} cm{}", point(range.near_point_m()),
                                                       point(range.far_point_m()), p.eye.eye.pupil_diameter_mm, p.display.distance_cm,
                                                       p.depth ? ", depth map" : "")
                                         : std::string("off"));
  fmt::print("  impaired {}\n", p.eye.impair.describe());
  if (!in.amsler) fmt::print("  time     {:.1f} ms per frame\n", frame_ms / in.frames.size());
  fmt::print("  wrote    {}{}{}\n", o.output, o.amsler.empty() ? "" : ", " + o.amsler, o.field_map.empty() ? "" : ", " + o.field_map);
}

int run_perceive(const PerceiveOptions& o) {
  const ThreadScope threads(o.threads);
  const Perceiver p = make_perceiver(o);
  if (!o.amsler.empty()) save_image(amsler_grid(*p.passes, 20), o.amsler);
  if (!o.field_map.empty()) write_field_picture(p.eye.impair.field, p.passes->field_map(), o.field_map);
  const PerceiveInput in = open_input(o);
  const PerceiveGaze gaze = open_gaze(o, in);
  const double frame_ms = see_frames(o, p, in, gaze);
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
  cmd->add_option("-o,--output", o->output, "the same kind as the input: an image file, a folder, a video file")->required();
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
  cmd->add_option("--amsler", o->amsler, "also write the Amsler grid as this eye sees it (PNG)");
  cmd->add_option("--field-map", o->field_map, "also write the visual field's loss map, ±30°, with the test locations (PNG)");
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
