// apps/compare_command.cpp — `foveal compare`: PSNR, SSIM and RMSE of an image against a
// reference, over the whole image and per eccentricity band around the gaze.
#include "commands.h"
#include "foveal/io/plot.h"
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/quality/compare.h"
#include "foveal/util/error.h"
#include "foveal/util/parse.h"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <memory>

namespace foveal::app {

std::function<int()> add_compare_command(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("compare", "PSNR, SSIM and RMSE of an image against a reference, whole and per eccentricity band around the gaze");
  struct Options {
    std::string a, b, b2, gaze, display = "47.5,30,60,1680,1050", json, markdown, error_map, plot, ssim_border = "reflect";
    double ellipse = 1.538;
    float error_scale = 0.1f;
    bool quiet = false;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("image", o->a, "the image to judge (PNG, EXR or PFM), e.g. a foveated render")->required();
  cmd->add_option("reference", o->b, "the reference of the same size, e.g. the full-frame render")->required();
  cmd->add_option("--reference2", o->b2,
                  "the reference rendered with another seed: each band's error is also given as a multiple of the reference's own noise");
  cmd->add_option("--gaze", o->gaze, "gaze point X,Y in image pixels (default: the image centre)");
  cmd->add_option(
         "--display", o->display,
         "display W_CM,H_CM,DIST_CM[,RES_X,RES_Y] the image filled (the bands' degrees); without a resolution the image size is used")
      ->capture_default_str();
  cmd->add_option("--ellipse", o->ellipse, "ROI ellipse ratio a of the q(E) = 1 region (as rendered)")->capture_default_str();
  cmd->add_option("--ssim-border", o->ssim_border,
                  "SSIM near the edges: reflect (the image mirrored, every pixel counts) or valid (only 11x11 windows wholly inside "
                  "the image count, as Wang et al.'s code and scikit-image)")
      ->capture_default_str();
  cmd->add_option("--json", o->json, "write every figure as JSON")->check(output_file());
  cmd->add_option("--markdown", o->markdown, "write the per-band table as Markdown")->check(output_file());
  cmd->add_option("--error-map", o->error_map, "per-pixel |image − reference| as a heat map (PNG)")->check(output_file(image_extensions()));
  cmd->add_option("--error-scale", o->error_scale, "the error the heat map's hottest colour stands for")->capture_default_str();
  cmd->add_option("--plot", o->plot, "RMSE against eccentricity in 1° bins (.png or .svg)")->check(output_file(plot_extensions()));
  cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");

  return [o] {
    auto load_finite = [](const std::string& path) {  // a NaN pixel would make every error NaN: "identical"
      Image im = load_image(path);
      const auto bad = std::count_if(im.pixels.begin(), im.pixels.end(), [](float v) { return !std::isfinite(v); });
      if (bad) fail("{}: {} NaN or infinite values; compare needs finite pixels", path, bad);
      return im;
    };
    const Image a = load_finite(o->a), b = load_finite(o->b);
    std::optional<Image> b2;
    if (!o->b2.empty()) b2 = load_finite(o->b2);
    const Display display = resolve_display(o->display, {a.width, a.height});
    const glm::dvec2 gaze = o->gaze.empty() ? glm::dvec2(a.width * 0.5, a.height * 0.5) : parse_vec2("--gaze", o->gaze);
    FoveationParams params;
    params.ellipse_ratio = o->ellipse;
    if (!(o->ellipse > 0)) fail("--ellipse: must be > 0, got {}", o->ellipse);
    if (!(o->error_scale > 0)) fail("--error-scale: must be > 0, got {}", o->error_scale);
    const SsimBorder border = parse_ssim_border(o->ssim_border);
    const Comparison c = compare_images(a, b, b2 ? &*b2 : nullptr, display, gaze, params, default_bands(), border);
    if (!o->error_map.empty()) save_image(error_map_image(c, o->error_scale), o->error_map, false);
    if (!o->plot.empty()) write_error_plot(c, o->plot);
    if (!o->json.empty()) {
      nlohmann::json j = comparison_json(c, display);
      j["image"] = o->a;
      j["reference"] = o->b;
      if (b2) j["reference2"] = o->b2;
      j["ssim_border"] = to_string(border);
      write_json_file(o->json, j);
    }
    if (!o->markdown.empty()) write_text_file(o->markdown, comparison_markdown(c));
    if (o->quiet) return 0;
    fmt::print("foveal compare: {} against {} ({}x{}, gaze {:.0f},{:.0f})\n", o->a, o->b, c.width, c.height, gaze.x, gaze.y);
    auto row = [&](const std::string& name, const ErrorStats& s) {
      fmt::print("  {:<8} {:>8} px  RMSE {:.5f}  PSNR {:>6}  SSIM {:.4f}", name, s.pixels, s.rmse,
                 std::isfinite(s.psnr) ? fmt::format("{:.2f}", s.psnr) : std::string("inf"), s.ssim);
    };
    row("whole", c.whole);
    if (c.whole_noise) fmt::print("   reference noise RMSE {:.5f}", c.whole_noise->rmse);
    fmt::print("\n");
    for (const BandResult& r : c.bands) {
      row(r.band.foveal_region ? "q(E)=1" : r.band.name + "°", r.error);
      if (r.noise && r.error.pixels > 0)
        fmt::print("   noise RMSE {:.5f}  ×{:.2f} ± {:.2f}{}", r.noise->rmse, r.noise_ratio, r.ratio_se,
                   r.within_noise ? "  within noise" : "");
      fmt::print("\n");
    }
    fmt::print("  acuity-weighted RMSE {:.5f}", c.weighted_rmse);
    if (b2) fmt::print("   noise {:.5f}  ×{:.2f}", c.weighted_noise_rmse, c.weighted_ratio());
    fmt::print("\n");
    return 0;
  };
}

}  // namespace foveal::app
