// apps/commands.h — the subcommands of the `foveal` executable.
#pragma once

#include "foveal/util/device.h"
#include "foveal/gaze/fixation.h"
#include "foveal/gaze/landing.h"
#include "foveal/perception/foveation.h"
#include "foveal/render/render.h"
#include "foveal/scene/scene.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace foveal::app {

// Each adds its subcommand to the app and returns the function that runs it after parsing.
std::function<int()> add_render_command(CLI::App& app);
std::function<int()> add_bench_command(CLI::App& app);
std::function<int()> add_gaze_command(CLI::App& app);
std::function<int()> add_replay_command(CLI::App& app);
std::function<int()> add_simulate_command(CLI::App& app);
std::function<int()> add_view_command(CLI::App& app);
std::function<int()> add_compare_command(CLI::App& app);
std::function<int()> add_perceive_command(CLI::App& app);
std::function<int()> add_bench_vision_command(CLI::App& bench);
std::function<int()> add_bench_blur_command(CLI::App& bench);
std::function<int()> add_bench_quality_command(CLI::App& bench);
std::function<int()> add_bench_latency_command(CLI::App& bench);
std::function<int()> add_bench_events_command(CLI::App& bench);
std::function<int()> add_bench_stalls_command(CLI::App& bench);

// A library error (util/error.h: it names parameters) in the command line's words: its options.
std::string cli_words(const std::string& message);

// Options shared by the commands that render: parsed text, turned into params by each command.
struct ViewOptions {
  std::string scene = "builtin:box";
  std::string camera;
  std::string eye, look, up = "0,1,0";
  std::string eye_option = "--eye";  // simulate calls the camera position --from (--eye is the eye model there)
  bool display_option = true;        // simulate has no display: the eye sits at the camera
  std::optional<double> fov;         // unset: the camera's
  std::string size = "840x525";
  std::string display = "47.5,30,60,1680,1050";
  int threads = 0;
};

// Options of the foveated-AO renderer shared by render and replay.
struct RenderOptions {
  std::string mode = "foveated", ao_distance, ambient = "1", trace_api = "stream";
  int max_rays = 400, min_rays = 0;
  double gamma = 2, beta = 0, ellipse = 1.538;
  uint64_t seed = 1;
  bool shadows = false;
  bool mode_option = true;  // view has its own --mode (foveated, reference, side-by-side, vision)
  // Quality per ray (AoReuseParams)
  bool adaptive = false, denoise = false, temporal = false;
  int adaptive_min_rays = 16, temporal_frames = 4, history_frames = 16, target_rays = 400;
  double denoise_radius = 1, tolerance = AoReuseParams{}.tolerance;
};
void add_render_options(CLI::App& command, RenderOptions& options);
// An output file's option: its folder must exist and be writable, and, where `extensions` are
// given, its name end in one of them — checked when the command line is read, not after the run
// (util/files.h check_output_file).
// Its name marks the option an output: main.cpp checks every output against the others and against
// the command's other arguments before the run (util/files.h check_outputs_apart).
CLI::Validator output_file(std::vector<std::string> extensions = {});
inline constexpr const char* kOutputFileValidator = "output-file";
// An output whose own check its command makes (-o of a folder or of any kind, --video and --stats
// beside a folder of outputs): marked so that main.cpp checks it against the other outputs and the
// inputs as well.
CLI::Validator an_output();
// A number of 0 or more: "must be 0 or more, got -1", and one above 0: "must be more than 0, got 0"
// (CLI11's NonNegativeNumber and PositiveNumber printed their range's upper end, the largest double,
// in full). Text that is no number is left to the option's own reading.
CLI::Validator non_negative();
CLI::Validator positive();
// An output file of a command that also writes a folder of outputs (`folder`, -o, which the run
// creates): a file in that folder, or one output_file accepts — but none of the files the command
// writes there (`written_there(name)`: `replay -o out --stats out/frames.csv` replaced the
// per-frame table). Checked before the run; throws Error naming `option`.
void check_output_beside_folder(const char* option, const std::string& path, const std::string& folder,
                                const std::function<bool(const std::string&)>& written_there);
// --device auto|cpu|cuda (see choose_device).
void add_device_option(CLI::App& command, std::string& device);
// --landing NAME=VALUE[,…]: the real-time loop's saccade landing predictor (gaze/landing.h);
// `needs`: what the option goes with, for its help ("" for none).
void add_landing_option(CLI::App& command, std::string& landing, const std::string& needs = "");
// --margin-ms and --periphery-share: how a real-time loop's frame keeps clear of the machine's own
// pauses, and --no-rays-ahead (render/realtime.h's LoopSettings; docs/realtime.md); unset: the loop's defaults.
// `needs`: what the options go with, for their help.
struct LoopOptions {
  std::optional<double> margin_ms, periphery_share;
  bool no_rays_ahead = false;       // --no-rays-ahead: a converged view casts nothing (LoopSettings::rays_ahead)
  std::optional<double> min_scale;  // --min-scale: the smallest size the loop may render at (LoopSettings::min_scale)
  bool given() const { return margin_ms || periphery_share || no_rays_ahead || min_scale; }
  const char* given_name() const {
    return margin_ms ? "--margin-ms" : periphery_share ? "--periphery-share" : no_rays_ahead ? "--no-rays-ahead" : "--min-scale";
  }
};
void add_loop_options(CLI::App& command, LoopOptions& loop, const std::string& needs);
// The predictor's parameters from --landing's text (the defaults where empty); `predicting`:
// whether the command's loop predicts at all (else a given --landing is refused); throws Error
// naming --landing.
LandingParams resolve_landing(const std::string& text, bool predicting = true);
// Size, display and renderer options → validated params (gaze unset).
RenderParams resolve_render_params(const ViewOptions& view, const RenderOptions& options);

// Camera from the options: a named one, explicit eye/look/up/fov, the scene's first, or a default.
Camera resolve_camera(const Scene& scene, const ViewOptions& options);
// Display from "W_CM,H_CM,DIST_CM[,RES_X,RES_Y]"; without a resolution the render size is used.
Display resolve_display(const std::string& text, glm::ivec2 render_size);
// Add the --scene/--camera/--eye/…/--threads options to a subcommand.
void add_view_options(CLI::App& command, ViewOptions& options);

// A scene JSON of the repository's scenes/ folder (from the working folder or the source tree),
// or "" when it is missing or the ../shared/data file it needs (`data_file`, relative) is absent.
std::string repository_scene(const std::string& file, const std::string& data_file = "");
// `spec` loaded, or when empty the paper's dragon box (scenes/dragon-box.json), or builtin:box
// when the dragon is absent (said on stdout); `spec` is set to what was loaded.
Scene load_paper_scene(std::string& spec, const std::string& command);

// Options that say how to read a recording and filter its fixations (gaze, replay).
struct GazeOptions {
  std::string format = "auto", screen, eye = "average", time_unit = "s", coords = "px", origin = "top-left";
  std::string fixations_file, blinks_file;
  double min_confidence = 0.6;
  std::string fixation = to_string(kRecommendedFixationMethod);
  double pursuit_velocity = 6, pursuit_window_ms = 40, min_pursuit_ms = 80;
  double ivt_threshold = 30, velocity_window_ms = 20, gap_fill_ms = 75, merge_gap_ms = 75, merge_angle = 0.5, min_fixation_ms = 60,
         idt_dispersion = 1.0, idt_duration_ms = 80;
  int median_window = 1;
};
// `fixation_help` replaces the --fixation description (simulate accepts other values).
void add_gaze_options(CLI::App& command, GazeOptions& options, const std::string& fixation_help = "");
// Reader options (screen for normalised coordinates defaults to the display's resolution).
ReadOptions resolve_read_options(const GazeOptions& options, const Display& display);
FixationParams resolve_fixation_params(const GazeOptions& options);
// read_recording, with the reader's warnings (a truncated file, …) on stderr.
Recording read_recording_warned(const std::string& path, const ReadOptions& options);

}  // namespace foveal::app
