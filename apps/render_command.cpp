// apps/render_command.cpp — `foveal render`: one frame of foveated (or full-frame) AO.
#include "commands.h"

#include "foveal/io/plot.h"
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/render.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/parallel.h"
#include "foveal/util/parse.h"
#include "foveal/util/timer.h"

#include <fmt/core.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>
#include <memory>

namespace foveal::app {

Camera resolve_camera(const Scene& scene, const ViewOptions& o) {
  Camera cam = !o.camera.empty() ? find_camera(scene, o.camera) : first_camera(scene);
  if (!o.eye.empty() != !o.look.empty()) fail("{} and --look must be given together", o.eye_option);
  if (!o.eye.empty()) {
    cam.name = "command line";
    cam.eye = parse_vec3(o.eye_option, o.eye);
    cam.look = parse_vec3("--look", o.look);
    cam.up = parse_vec3("--up", o.up);
    if (glm::length(cam.look - cam.eye) == 0) fail("{} and --look must differ", o.eye_option);
    if (glm::length(glm::cross(cam.look - cam.eye, cam.up)) == 0) fail("--up must not be parallel to the view direction");
  }
  if (o.fov) {  // given: the open range (0, 180) at both ends, 0 included
    if (!(*o.fov > 0 && *o.fov < 180)) fail("--fov: must be in (0, 180) degrees, got {}", *o.fov);
    cam.fov_deg = static_cast<float>(*o.fov);
  }
  return cam;
}

void add_view_options(CLI::App& cmd, ViewOptions& o) {
  cmd.add_option("--scene", o.scene, "mesh file (OBJ, PLY, glTF, … via Assimp), scene .json, or builtin:box|sphere-plane|plane")
      ->capture_default_str();
  cmd.add_option("--camera", o.camera, "named camera of the scene (default: its first, or one framing the scene)");
  cmd.add_option(o.eye_option, o.eye, "camera position X,Y,Z (scene units; with --look)");
  cmd.add_option("--look", o.look, "point looked at X,Y,Z (scene units)");
  cmd.add_option("--up", o.up, "up vector X,Y,Z")->capture_default_str();
  cmd.add_option("--fov", o.fov, "vertical field of view, degrees (default: the camera's)");
  cmd.add_option("--size", o.size, "image size WxH in pixels")->capture_default_str();
  if (o.display_option)
    cmd.add_option("--display", o.display, "display W_CM,H_CM,DIST_CM[,RES_X,RES_Y]; without a resolution the render size is used")
        ->capture_default_str();
  cmd.add_option("--threads", o.threads, "worker threads (0 = all cores)")->capture_default_str()->check(CLI::Range(0, 4096));
}

CLI::Validator output_file(std::vector<std::string> extensions) {
  return CLI::Validator(
      [extensions](std::string& path) {
        try {
          check_output_file(path, extensions);
        } catch (const Error& e) {
          return std::string(e.what());
        }
        return std::string();
      },
      "FILE", kOutputFileValidator);
}

namespace {

// A number's lower bound (0, and whether 0 itself is taken) as a validator
CLI::Validator at_least_zero(bool zero_taken) {
  return CLI::Validator(
      [zero_taken](std::string& value) {
        char* end = nullptr;
        const double x = std::strtod(value.c_str(), &end);
        if (end == value.c_str() || *end != '\0' || x > 0 || (zero_taken && x == 0)) return std::string();
        return zero_taken ? fmt::format("must be 0 or more, got {}", value) : fmt::format("must be more than 0, got {}", value);
      },
      zero_taken ? "NONNEGATIVE" : "POSITIVE");
}

}  // namespace

CLI::Validator non_negative() { return at_least_zero(true); }
CLI::Validator positive() { return at_least_zero(false); }

CLI::Validator an_output() {
  return CLI::Validator([](std::string&) { return std::string(); }, "", kOutputFileValidator);
}

void check_output_beside_folder(const char* option, const std::string& path, const std::string& folder,
                                const std::function<bool(const std::string&)>& written_there) {
  if (path.empty()) return;
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto place = [&ec](const fs::path& p) {
    fs::path r = fs::weakly_canonical(fs::absolute(p), ec).lexically_normal();
    return r.has_filename() ? r : r.parent_path();  // "out/"
  };
  const fs::path file = place(path);
  if (!folder.empty() && file.parent_path() == place(folder)) {
    const std::string name = file.filename().string();
    if (written_there(name)) fail("{} {}: is a file this command writes into {} ({}); give it another name", option, path, folder, name);
    return;  // the folder is the run's: created with its outputs
  }
  try {
    check_output_file(path);
  } catch (const Error& e) {
    fail("{}: {}", option, e.what());
  }
}

void add_device_option(CLI::App& cmd, std::string& device) {
  cmd.add_option("--device", device, "where the passes run: auto (cuda when a usable NVIDIA GPU is present, else cpu), cpu or cuda")
      ->capture_default_str();
}

void add_landing_option(CLI::App& cmd, std::string& landing, const std::string& needs) {
  std::string names;  // each parameter with its default
  for (const auto& [name, value] : landing_parameters(LandingParams{}))
    names += fmt::format("{}{} ({:g})", names.empty() ? "" : ", ", name, value);
  cmd.add_option("--landing", landing,
                 needs + "the saccade landing predictor's parameters, NAME=VALUE[,…]: " + names + " (docs/realtime.md)");
}

void add_loop_options(CLI::App& cmd, LoopOptions& loop, const std::string& needs) {
  cmd.add_option("--margin-ms", loop.margin_ms,
                 needs +
                     "the least time each frame keeps free for the machine's pauses, ms (default 2, or a quarter of a shorter "
                     "budget; more after frames that ended late, up to a quarter of the budget; wall clock)");
  cmd.add_option("--periphery-share", loop.periphery_share,
                 needs +
                     "the periphery's rays stop once the frame has spent this share of its budget; the fovea's go on to the "
                     "deadline (default 1: the periphery's too; 0.6 had a quarter of the late frames on a busy 2-core machine, "
                     "and a fresh view's landings waited longer: docs/realtime.md)");
  cmd.add_flag("--no-rays-ahead", loop.no_rays_ahead,
               needs +
                   "once every pixel has its n(E), cast nothing more (by default the frames' spare time, up to half of each budget, "
                   "takes every pixel on to n_max, nearest the gaze first, for where the eye lands next: docs/realtime.md)");
  cmd.add_option("--min-scale", loop.min_scale,
                 needs +
                     "the smallest size the loop may render at where its base shading does not fit the budget, a share of the "
                     "size asked for in (0, 1] (default 0.25; 1: the stimulus keeps its resolution throughout, and such frames "
                     "come late instead, the loop saying so: docs/realtime.md)");
}

LandingParams resolve_landing(const std::string& text, bool predicting) {
  if (!text.empty() && !predicting) fail("--landing: needs --realtime with its prediction (no --no-predict)");
  try {
    return parse_landing_params(text);
  } catch (const Error& e) {
    fail("--landing: {}", e.what());
  }
}

void add_render_options(CLI::App& cmd, RenderOptions& o) {
  if (o.mode_option)
    cmd.add_option("--mode", o.mode, "foveated (budget follows the gaze) or full (n_max rays everywhere: the reference)")
        ->capture_default_str();
  cmd.add_option("--ao-distance", o.ao_distance,
                 "AO ray length in scene units, or inf (default: scene's, else 0.2 × bounding-box diagonal)");
  cmd.add_option("--max-rays", o.max_rays, "n_max: AO rays per pixel where q(E) = 1")->capture_default_str();
  cmd.add_option("--min-rays", o.min_rays, "n_min: AO rays per pixel far from the gaze")->capture_default_str();
  cmd.add_option("--gamma", o.gamma, "γ: exponent of q(E) in the ray budget n(E)")->capture_default_str();
  cmd.add_option("--beta", o.beta, "β: exponent of q(E) in the AO blend weight b(E)")->capture_default_str();
  cmd.add_option("--ellipse", o.ellipse, "horizontal:vertical ratio a of the elliptical ROI (1 = circle)")->capture_default_str();
  cmd.add_option("--ambient-constant", o.ambient,
                 "k_const, the Phong ambient factor away from the gaze: a number, or auto (mean AO visibility of the fovea)")
      ->capture_default_str();
  cmd.add_option("--seed", o.seed, "seed of the AO ray directions")->capture_default_str();
  cmd.add_option("--trace-api", o.trace_api, "how occlusion rays go to Embree: stream, packet8 or single")->capture_default_str();
  cmd.add_flag("--shadows", o.shadows, "cast shadow rays for the lights (off, as in the papers)");
  // Quality per ray (docs/quality.md, "More quality per ray")
  const std::string group = "Quality per ray (all off: the paper's method)";
  cmd.add_flag("--adaptive", o.adaptive,
               "cast each pixel's rays in doubling rounds and stop once its standard error is below τ(E) (n(E) becomes a maximum)")
      ->group(group);
  cmd.add_option("--adaptive-min-rays", o.adaptive_min_rays, "--adaptive: rays of the first round")->capture_default_str()->group(group);
  cmd.add_flag("--denoise", o.denoise, "edge-stopping filter (depth, normal, albedo) of AO where a pixel is noisier than τ(E)")
      ->group(group);
  cmd.add_option("--denoise-radius", o.denoise_radius,
                 "--denoise: the footprint is radius·(1/q(E) − 1) pixels, at most 8 (none where q = 1)")
      ->capture_default_str()
      ->group(group);
  cmd.add_flag("--temporal", o.temporal, "accumulate AO rays across frames, reprojected with the camera, history rejected on disocclusion")
      ->group(group);
  cmd.add_option("--temporal-frames", o.temporal_frames, "--temporal: F, a pixel with n(E) rays of history casts n(E)/F a frame")
      ->capture_default_str()
      ->group(group);
  cmd.add_option("--history-frames", o.history_frames, "--temporal: history length where q = 1, frames (max(F, H·q(E)) elsewhere)")
      ->capture_default_str()
      ->group(group);
  cmd.add_option("--target-rays", o.target_rays, "the reference whose noise sets τ(E) = 0.5/√N / q(E), rays per pixel")
      ->capture_default_str()
      ->group(group);
  cmd.add_option("--tolerance", o.tolerance, "scales τ(E) (above 1: fewer rays, more noise)")->capture_default_str()->group(group);
}

RenderParams resolve_render_params(const ViewOptions& view, const RenderOptions& o) {
  RenderParams p;
  const glm::ivec2 size = parse_size("--size", view.size);
  p.width = size.x;
  p.height = size.y;
  p.mode = parse_render_mode(o.mode);
  p.display = resolve_display(view.display, size);
  p.foveation = {o.ellipse, o.max_rays, o.min_rays, o.gamma, o.beta};
  if (!o.ao_distance.empty()) p.ao_distance = parse_length_or_inf("--ao-distance", o.ao_distance);
  if (o.ambient == "auto")
    p.ambient_constant.reset();
  else
    p.ambient_constant = static_cast<float>(parse_numbers("--ambient-constant", o.ambient, 1)[0]);
  p.seed = o.seed;
  p.shadows = o.shadows;
  p.reuse.adaptive = o.adaptive;
  p.reuse.adaptive_min_rays = o.adaptive_min_rays;
  p.reuse.denoise = o.denoise;
  p.reuse.denoise_radius = o.denoise_radius;
  p.reuse.temporal = o.temporal;
  p.reuse.temporal_frames = o.temporal_frames;
  p.reuse.history_frames = o.history_frames;
  p.reuse.target_rays = o.target_rays;
  p.reuse.tolerance = o.tolerance;
  validate(p);
  return p;
}

Display resolve_display(const std::string& text, glm::ivec2 size) {
  Display defaults;
  defaults.res_x = size.x;
  defaults.res_y = size.y;
  return parse_display(text, defaults);
}

namespace {

// The command's options as typed.
struct RenderCommandOptions {
  ViewOptions view;
  RenderOptions render;
  std::string gaze, output = "render.png", aov, mask, stats, plot, device = "auto";
  int frames = 1;
  bool quiet = false;
};

// Options → params (all checked before any work), the frames through the device-neutral renderer, the outputs.
int run_render(const RenderCommandOptions& o) {
  const ThreadScope threads(o.view.threads);
  // Options → params (all validated before any work)
  RenderParams p = resolve_render_params(o.view, o.render);
  if (!o.gaze.empty()) p.gaze_px = parse_vec2("--gaze", o.gaze);
  const TraceApi api = parse_trace_api(o.render.trace_api);
  if (!o.plot.empty()) write_acuity_plot(p.display, p.foveation, o.plot);

  const ComputeDevice device = choose_device(o.device);
  if (o.frames > 1 && !p.reuse.temporal) fail("--frames: {} frames of a still view are the same image without --temporal", o.frames);

  // Scene, renderer (it keeps the --temporal history between its frames), frames
  const Scene scene = load_scene(o.view.scene);
  const Camera camera = resolve_camera(scene, o.view);
  const std::unique_ptr<FrameRenderer> renderer = make_frame_renderer(scene, device, api);
  // A progress line on a terminal, for renders long enough to wait for
  const bool show_progress = !o.quiet && isatty(fileno(stderr));
  const Timer clock;
  int shown = -1;
  Frame frame;
  uint64_t ao_rays = 0;
  for (int k = 0; k < o.frames; ++k) {
    FrameOptions options;
    options.progress = [&](double fraction) {
      const int percent = static_cast<int>(fraction * 100);
      if (!show_progress || percent == shown || clock.ms() < 1000) return;
      shown = percent;
      if (o.frames > 1)
        fmt::print(stderr, "\r  frame {}/{}  AO {:3d}%  {:.1f} s", k + 1, o.frames, percent, clock.ms() / 1000);
      else
        fmt::print(stderr, "\r  AO {:3d}%  {:.1f} s", percent, clock.ms() / 1000);
    };
    frame = renderer->render(camera, p, options);
    ao_rays += frame.stats.ao_rays;
  }
  if (shown >= 0) fmt::print(stderr, "\r{:50}\r", "");
  const size_t triangles = renderer->triangles();
  const double build_ms = renderer->build_ms();
  if (o.frames > 1 && !o.quiet)
    fmt::print("  {} frames accumulated: {:.2f} M AO rays in all; the last frame's figures follow\n", o.frames, ao_rays / 1e6);

  // Outputs
  save_image(frame.color, o.output);
  if (!o.aov.empty()) write_aovs(frame, o.aov);
  if (!o.mask.empty()) save_image(budget_mask(frame, p.foveation.max_rays), o.mask, false);
  if (!o.stats.empty())
    write_json_file(o.stats,
                    frame_stats_json(frame, p, scene, triangles, build_ms, threads.threads(), to_string(device), renderer->trace_api()));
  if (o.quiet) return 0;
  const FrameStats& s = frame.stats;
  fmt::print("foveal render: {} ({} triangles{}, BVH {:.0f} ms), camera '{}', {}x{}, {} mode, gaze ({:.0f}, {:.0f}), {} threads\n",
             scene.source, triangles,
             scene.skipped_triangles ? fmt::format(", {} degenerate or out of range skipped", scene.skipped_triangles) : "", build_ms,
             camera.name, p.width, p.height, to_string(p.mode), frame.gaze_px.x, frame.gaze_px.y, threads.threads());
  fmt::print("  device   {}\n", renderer->describe());
  fmt::print("  AO rays  {:.2f} M ({:.1f} per pixel, {}..{}), {:.1f} Mrays/s\n", s.ao_rays / 1e6, s.ao_rays_mean, s.ao_rays_min,
             s.ao_rays_max, s.ao_ms > 0 ? s.ao_rays / (s.ao_ms * 1e3) : 0.0);
  fmt::print("  time     primary {:.1f} ms, foveation {:.1f} ms, AO {:.1f} ms, shade {:.1f} ms, total {:.1f} ms\n", s.primary_ms,
             s.foveation_ms, s.ao_ms, s.shade_ms, s.total_ms);
  if (p.reuse.any())
    fmt::print("  reuse    {}{}{}, history kept at {} pixels, {} pixels filtered, {:.1f} ms\n", p.reuse.adaptive ? "adaptive " : "",
               p.reuse.denoise ? "denoise " : "", p.reuse.temporal ? "temporal" : "", s.history_pixels, s.denoised_pixels, s.reuse_ms);
  fmt::print("  wrote    {}", o.output);
  for (const auto& extra : {o.mask, o.stats, o.plot})
    if (!extra.empty()) fmt::print(", {}", extra);
  if (!o.aov.empty()) fmt::print(", AOVs {}", o.aov);
  fmt::print("\n");
  return 0;
}

}  // namespace

std::function<int()> add_render_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "render one frame with gaze-dependent ambient occlusion");

  auto o = std::make_shared<RenderCommandOptions>();
  add_view_options(*cmd, o->view);
  cmd->add_option("--gaze", o->gaze, "gaze point X,Y in render pixels, origin top-left (default: image centre; may lie off the image)");
  add_render_options(*cmd, o->render);
  add_device_option(*cmd, o->device);
  cmd->add_option("-o,--output", o->output, "shaded image (.png; .pfm/.exr keep linear floats)")
      ->capture_default_str()
      ->check(output_file(image_extensions()));
  cmd->add_option("--aov", o->aov,
                  "float buffers NAME=FILE[,…] as .pfm/.exr; names: ao, depth, position, normal, albedo, budget, quality, blend, "
                  "eccentricity, traced (AO rays traced this frame)");
  cmd->add_option("--mask", o->mask, "ROI/budget mask of the paper's Figure 5 (PNG): grey = n(E)/n_max, red cross at the gaze")
      ->check(output_file(image_extensions()));
  cmd->add_option("--acuity-plot", o->plot, "plot of the acuity model (paper's Figure 4) for the display, .svg or .png")
      ->check(output_file(plot_extensions()));
  cmd->add_option("--stats", o->stats, "write timings and ray counts as JSON")->check(output_file());
  cmd->add_option(
         "--frames", o->frames,
         "with --temporal: render this many frames of the still camera and gaze, each from the last one's history; the last is written")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");

  return [o] { return run_render(*o); };
}

}  // namespace foveal::app
