// foveal/render/outputs.h — what `render` writes besides the image: AOVs, the budget mask of the
// paper's Figure 5, the acuity plot of its Figure 4, and the stats JSON of the CLI contract.
#pragma once

#include "foveal/perception/foveation.h"
#include "foveal/render/render.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace foveal {

// Names accepted by aov_image(): ao, depth, position, normal, albedo, budget, quality, blend, eccentricity.
std::vector<std::string> aov_names();
// One float buffer of a frame. Pixels that hit nothing hold NaN (position, normal, depth, albedo)
// or 1 (ao); budget is n(E) in rays, eccentricity in degrees.
Image aov_image(const Frame& frame, const std::string& name);
// Write "name=file,name=file" (file extension .pfm or .exr); throws Error for an unknown name.
void write_aovs(const Frame& frame, const std::string& spec);

// The region-of-interest mask (Figure 5): grey = n(E)/n_max, lighter = more AO rays, with the
// gaze marked by a red cross when it is on the image.
Image budget_mask(const Frame& frame, int max_rays);

// `image` at width × height, nearest pixel (a real-time frame rendered smaller than asked, shown at
// the size asked; the image itself where it already has that size).
Image scaled_nearest(const Image& image, int width, int height);

// Draw a red diagonal cross at a render position (nothing where it falls off the image).
void mark_gaze(Image& image, glm::dvec2 gaze_px);

// Plot of the acuity model (Figure 4) for a display: f_c(E) of eq. 4, the display's limit
// (magenta), and the resulting AO budget n(E). Written as .svg or .png.
void write_acuity_plot(const Display& display, const FoveationParams& params, const std::string& path);

// The `--stats` JSON of the CLI contract for one frame.
nlohmann::json frame_stats_json(const Frame& frame, const RenderParams& params, const Scene& scene, size_t bvh_triangles, double build_ms,
                                int threads, const std::string& device,
                                const std::string& trace_api);  // device "cpu"/"cuda", trace API "stream", … or "bvh2"

// Peak resident memory of this process so far, MiB.
double peak_rss_mib();

// Write text to a file, replacing it; throws Error naming the file when it cannot.
void write_text_file(const std::string& path, const std::string& text);
// The same for JSON (indented by two, a final newline).
void write_json_file(const std::string& path, const nlohmann::json& json);

}  // namespace foveal
