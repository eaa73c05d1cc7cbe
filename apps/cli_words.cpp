// apps/cli_words.cpp — library errors in the command line's words: each parameter the library
// names (util/error.h) becomes the option a user of `foveal` typed.
#include "commands.h"

#include "foveal/util/error.h"

#include <array>

namespace foveal::app {

namespace {

// Library parameter → option. Parameters in seconds whose options are in milliseconds are not
// here: the commands check those options themselves, in milliseconds (apps/gaze_command.cpp).
constexpr std::array kOptions = std::to_array<ParameterName>({
    // render, replay, view: RenderParams, AoReuseParams, ReplaySettings
    {"mode", "--mode"},
    {"size", "--size"},
    {"max_rays", "--max-rays"},
    {"min_rays", "--min-rays"},
    {"gamma", "--gamma"},
    {"beta", "--beta"},
    {"ellipse_ratio", "--ellipse"},
    {"ao_distance", "--ao-distance"},
    {"ambient_constant", "--ambient-constant"},
    {"gaze_px", "--gaze"},
    {"fixation_px", "the fixation"},
    {"adaptive_min_rays", "--adaptive-min-rays"},
    {"denoise_radius", "--denoise-radius"},
    {"temporal_frames", "--temporal-frames"},
    {"history_frames", "--history-frames"},
    {"target_rays", "--target-rays"},
    {"tolerance", "--tolerance"},
    {"aov", "--aov"},
    {"display", "--display"},
    {"subject", "--subject"},
    {"task", "--task"},
    {"session", "--session"},
    {"run", "--run"},
    {"fps", "--fps"},
    {"orbit_deg_s", "--orbit"},
    {"depth", "--depth"},
    {"frames", "--frames"},
    {"start_s", "--start"},
    {"duration_s", "--duration"},
    {"live_timeout_s", "--live-timeout"},
    {"device", "--device"},
    // the real-time loop and bench latency
    {"frame_budget_ms", "--frame-budget-ms"},
    {"refresh_hz", "--refresh-hz"},
    {"latency_ms", "--latency-ms"},
    {"min_amplitude_deg", "--min-amplitude"},
    {"clock", "--clock"},
    {"loops", "--loops"},
    {"timeline", "--timeline"},
    {"model_rays_per_ms", "--model-rays-per-ms"},
    {"model_fixed_ms", "--model-fixed-ms"},
    {"margin_ms", "--margin-ms"},
    {"periphery_share", "--periphery-share"},
    {"min_scale", "--min-scale"},
    {"threshold_ms", "--threshold-ms"},
    {"chunk_us", "--chunk-us"},
    {"device cuda", "--device cuda"},
    // the eye, the vision simulation, the viewer, compare
    {"eye", "--eye"},
    {"pupil_diameter_mm", "--pupil"},
    {"image_distance_mm", "--image-distance"},
    {"lens_samples", "--lens-samples"},
    {"fast_threshold", "--fast-threshold"},
    {"blink_every", "--blink-every"},
    {"sharp_px", "--sharp-px"},
    {"saccade_max_deg", "--saccade-max"},
    {"saccade_min_deg", "--saccade-min"},
    {"voxel", "--voxel"},
    {"starvation", "--starvation"},
    {"blur_taps", "--blur-taps"},
    {"diff_gain", "--diff-gain"},
    {"overlays", "--overlays"},
    {"ssim_border", "--ssim-border"},
    // gaze: recordings, fixation filters, event detection
    {"format", "--format"},
    {"gaze_eye", "--gaze-eye"},
    {"stimulus", "--stimulus"},
    {"fixation", "--fixation"},
    {"events", "--events"},
    {"median_window", "--median-window"},
    {"velocity_threshold_deg_s", "--ivt-threshold"},
    {"merge_angle_deg", "--merge-angle"},
    {"dispersion_deg", "--idt-dispersion"},
    {"pursuit_velocity_deg_s", "--pursuit-velocity"},
    {"ek_lambda", "--ek-lambda"},
});

}  // namespace

std::string cli_words(const std::string& message) { return in_words(message, kOptions); }

}  // namespace foveal::app
