// python/src/bindings.h — what the parts of foveal._core share.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nlohmann/json.hpp>

#include "foveal/gaze/detect.h"
#include "foveal/gaze/landing.h"
#include "foveal/gaze/recording.h"
#include "foveal/util/image.h"

#include <initializer_list>
#include <vector>

namespace nb = nanobind;
using namespace nb::literals;

namespace foveal::python {

// A JSON document as Python objects (through the json module: dicts, lists, numbers, strings).
nb::object to_python(const nlohmann::json& j);
// A C-contiguous float32 H×W×C array, and the library's image of it (a copy).
using FloatImage = nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>;
Image image_from(const FloatImage& array);
Image image_from(const float* pixels, int width, int height, int channels);  // interleaved rows, top first
// A gaze point more than the frame's own size off a width × height frame is legal (the whole frame
// is then far periphery) but rarely meant: a Python UserWarning naming `name` says so (beyond the
// library's reach it raises instead). Returns whether it warned.
bool warn_if_far(const char* name, double x, double y, int width, int height);
// A NumPy array that owns `values`.
nb::ndarray<nb::numpy, float> owned_array(std::vector<float>&& values, std::initializer_list<size_t> shape);

// foveal._core's gaze functions (gaze.cpp).
void bind_gaze(nb::module_& m);
// A recording from foveal.gaze's columns (t_s, x, y, confidence, valid, pupil, screen; directions
// and block_starts when given).
Recording recording_from(const nb::dict& columns);
// The filter's (and, given `events`, the detectors') parameters by keyword; throws Error naming one
// it does not know.
void set_parameters(const nb::dict& params, FixationParams& fixation, EventParams* events);
// The saccade landing predictor's parameters by keyword (gaze/landing.h) over `base`, checked;
// throws Error naming one it does not know or that is no number.
LandingParams landing_params(const nb::dict& params, LandingParams base = {});
// The same from what a Loop or bench_latency takes as `landing`: None (the defaults), a dict by
// keyword, or the text of --landing ("NAME=VALUE,…"); throws TypeError for anything else.
LandingParams landing_params_of(const nb::handle& landing);
// foveal._core's perceive (perceive.cpp).
void bind_perceive(nb::module_& m);

}  // namespace foveal::python
