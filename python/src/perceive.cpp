// python/src/perceive.cpp — foveal._core's perceive: the library's Perceiver and perceive driver
// (experiments/perceive.h, what `foveal perceive` runs) on NumPy frames or on files.
#include "bindings.h"

#include "foveal/experiments/perceive.h"
#include "foveal/impair/profile.h"
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"
#include "foveal/util/parallel.h"

#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <algorithm>

namespace foveal::python {

namespace {

using AnyImage = nb::ndarray<nb::ndim<3>, nb::c_contig, nb::device::cpu>;
using Points = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;

// A frame as given: float32 values as they are; uint8/uint16 as load_image reads a file's (0–1)
Image frame_of(const AnyImage& a, size_t k) {
  const int w = static_cast<int>(a.shape(1)), h = static_cast<int>(a.shape(0)), c = static_cast<int>(a.shape(2));
  if (a.dtype() == nb::dtype<uint8_t>()) return image_from_integers(a.data(), w, h, c, 8);
  if (a.dtype() == nb::dtype<uint16_t>()) return image_from_integers(a.data(), w, h, c, 16);
  if (a.dtype() != nb::dtype<float>()) fail("image: frame {}: float32, uint8 or uint16 pixels", k);
  return image_from(static_cast<const float*>(a.data()), w, h, c);
}

nb::object array_of(Image&& img) {
  const size_t h = img.height, w = img.width, c = img.channels;
  return nb::cast(owned_array(std::move(img.pixels), {h, w, c}));
}

}  // namespace

void bind_perceive(nb::module_& m) {
  m.def(
      "_srgb_to_linear",
      [](const AnyImage& a) {
        Image img = frame_of(a, 0);
        for (size_t i = 0; i < img.pixels.size(); ++i)
          if (img.channels != 4 || i % 4 != 3) img.pixels[i] = srgb_to_linear(img.pixels[i]);  // alpha is no colour
        return array_of(std::move(img));
      },
      "image"_a);

  m.def(
      "_perceive",
      [](const std::vector<AnyImage>& frames, bool srgb, const std::string& path, const std::string& output, const std::string& eye,
         std::optional<double> pupil_mm, std::array<double, 5> display, std::optional<FloatImage> depth, bool optics, int blur_taps,
         double fps, std::optional<std::array<double, 2>> point, std::optional<Points> points, std::optional<nb::dict> recording,
         const std::string& fixation, const nb::dict& fixation_params, double start_s, const std::string& stimulus,
         int threads) -> nb::object {
        if (threads < 0) fail("threads: must be 0 (all cores) or more, got {}", threads);
        PerceiveParams p;
        p.eye = resolve_eye(eye, {pupil_mm, std::nullopt});
        p.optics = optics;
        p.blur.taps = blur_taps;
        p.display = Display{display[0], display[1], display[2], static_cast<int>(display[3]), static_cast<int>(display[4])};
        if (p.display.res_x > 0) validate(p.display);
        if (depth) {
          if (depth->shape(2) != 1) fail("depth: expected one channel of metres (H×W), got {}", depth->shape(2));
          p.depth = image_from(*depth);
        }
        if (!(fps > 0 && std::isfinite(fps))) fail("fps: must be positive, got {}", fps);
        // Each frame's gaze: a point, a recording's fixations, or one point per frame
        FrameGaze gaze;
        if (point) gaze = FrameGaze(glm::dvec2((*point)[0], (*point)[1]));
        if (recording) {
          const Recording r = recording_from(*recording);
          FixationParams params;
          set_parameters(fixation_params, params, nullptr);
          Display screen = p.display;
          if (screen.res_x <= 0) screen.res_x = Display{}.res_x, screen.res_y = Display{}.res_y;  // as the command line's
          gaze = FrameGaze(r, screen, parse_step_fixations(fixation), params, start_s, stimulus);
        } else if (!(start_s >= 0 && std::isfinite(start_s))) {
          fail("start_s: must be a finite number of seconds >= 0, got {}", start_s);
        }
        std::vector<Image> in;
        for (const AnyImage& a : frames) in.push_back(stimulus_to_linear(frame_of(a, in.size()), srgb, "image"));
        // A gaze far off its frame warns (once), as Renderer.render and VisionSimulation.step do
        const size_t given = points ? std::min<size_t>(points->shape(0), in.size()) : point ? in.size() : 0;
        for (size_t k = 0; k < given; ++k) {
          const double x = points ? points->data()[2 * k] : (*point)[0], y = points ? points->data()[2 * k + 1] : (*point)[1];
          if (warn_if_far("gaze", x, y, in[k].width, in[k].height)) break;
        }
        std::vector<Image> seen;
        {
          nb::gil_scoped_release release;
          const ThreadScope scope(threads);
          const Perceiver perceiver(std::move(p));
          if (!path.empty()) {
            const PerceiveInput files = open_perceive_input(path, output, fps);
            if (points) fail("gaze: one point per frame is for frames given as arrays; for files give a point or a recording");
            if (!output.empty())
              perceive_files(perceiver, files, gaze, output);
            else
              seen = perceive_frames(perceiver, files, gaze);
          } else {
            if (points && points->shape(0) != in.size()) fail("gaze: {} points for {} frames", points->shape(0), in.size());
            for (size_t k = 0; k < in.size(); ++k) {
              const glm::dvec2 g =
                  points ? glm::dvec2(points->data()[2 * k], points->data()[2 * k + 1]) : gaze.at(k, fps, in[k].width, in[k].height);
              seen.push_back(perceiver.see(in[k], g));
            }
          }
        }
        if (!output.empty()) return nb::none();
        nb::list out;
        for (Image& img : seen) out.append(array_of(std::move(img)));
        return out;
      },
      "frames"_a, "srgb"_a, "path"_a, "output"_a, "eye"_a, "pupil_mm"_a, "display"_a, "depth"_a, "optics"_a, "blur_taps"_a, "fps"_a,
      "point"_a, "points"_a, "recording"_a, "fixation"_a, "fixation_params"_a, "start_s"_a, "stimulus"_a, "threads"_a);
}

}  // namespace foveal::python
