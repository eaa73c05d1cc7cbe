// python/src/module.cpp — foveal._core: the Python module over the library the command line uses.
//
// Nothing here computes anything of its own: each call fills the same parameter structs the CLI
// fills and calls the same library functions. Images of a rendered frame are NumPy views of the
// frame's own buffers (no copy; they keep the frame alive), and the GIL is released while the
// library works, so that other Python threads (a tracker's, a window's) run meanwhile.
#include "bindings.h"

#include "foveal/experiments/latency.h"
#include "foveal/io/plot.h"
#include "foveal/experiments/stalls_report.h"
#include "foveal/impair/profile.h"
#include "foveal/io/image_io.h"
#include "foveal/render/outputs.h"
#include "foveal/quality/compare.h"
#include "foveal/render/render.h"
#include "foveal/render/frame_renderer.h"
#include "foveal/render/realtime.h"
#include "foveal/util/cpu_share.h"
#include "foveal/util/device.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/gaze_point.h"
#include "foveal/util/parallel.h"
#include "foveal/util/text.h"
#include "foveal/util/timer.h"
#include "foveal/vision/simulate.h"

#include <nanobind/stl/array.h>
#include <nanobind/stl/filesystem.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>

namespace foveal::python {

nb::object to_python(const nlohmann::json& j) { return nb::module_::import_("json").attr("loads")(j.dump()); }

nb::ndarray<nb::numpy, float> owned_array(std::vector<float>&& values, std::initializer_list<size_t> shape) {
  auto* data = new std::vector<float>(std::move(values));
  nb::capsule owner(data, [](void* p) noexcept { delete static_cast<std::vector<float>*>(p); });
  return nb::ndarray<nb::numpy, float>(data->data(), shape, owner);
}

bool warn_if_far(const char* name, double x, double y, int width, int height) {
  if (!(x < -width || x > 2.0 * width || y < -height || y > 2.0 * height)) return false;
  // A point the renderers refuse (not finite, or beyond kGazeReachImages image sizes) gets their
  // error alone, not a warning before it
  if (!gaze_point_near(x, y, width, height)) return false;
  const std::string message = fmt::format(
      "{}: ({}, {}) is more than the frame's size ({}x{}) off the frame: the whole image is far periphery", name, x, y, width, height);
  if (PyErr_WarnEx(PyExc_UserWarning, message.c_str(), 1) != 0) throw nb::python_error();  // warnings turned into errors
  return true;
}

Image image_from(const float* pixels, int width, int height, int channels) {
  Image img(width, height, channels);
  std::memcpy(img.pixels.data(), pixels, img.pixels.size() * sizeof(float));
  return img;
}

Image image_from(const FloatImage& a) {
  return image_from(a.data(), static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), static_cast<int>(a.shape(2)));
}

namespace {

using Vec3 = std::array<float, 3>;
glm::vec3 vec(const Vec3& v) { return {v[0], v[1], v[2]}; }
Vec3 tuple(glm::vec3 v) { return {v.x, v.y, v.z}; }

// A scene shared by the renderers and simulations made from it.
struct PyScene {
  std::shared_ptr<const Scene> scene;

  static PyScene load(const std::filesystem::path& path) {
    const std::string spec = path.string();
    nb::gil_scoped_release release;
    return {std::make_shared<const Scene>(load_scene(spec))};
  }
};

// A scene argument: a Scene, or what the command line's --scene takes (a path, an os.PathLike or builtin:NAME), loaded then;
// a file that does not load is its loader's error, naming the file.
PyScene scene_of(const nb::object& scene) {
  if (nb::isinstance<PyScene>(scene)) return nb::cast<const PyScene&>(scene);
  std::filesystem::path path;
  if (!nb::try_cast<std::filesystem::path>(scene, path))
    throw nb::type_error(fmt::format("scene: a foveal.Scene, a path or builtin:box|sphere-plane|plane, got {}",
                                     nb::cast<std::string>(nb::str(scene.type().attr("__name__"))))
                             .c_str());
  return PyScene::load(path);
}

// The camera to use: a Camera, a camera name of the scene, or None (the scene's first, or one framing it).
Camera resolve_camera(const Scene& scene, const nb::object& camera) {
  if (camera.is_none()) return first_camera(scene);
  if (nb::isinstance<nb::str>(camera)) return find_camera(scene, nb::cast<std::string>(camera));
  Camera out;
  if (!nb::try_cast<Camera>(camera, out))
    throw nb::type_error(fmt::format("camera: a camera name (str), a foveal.Camera or None, got {}",
                                     nb::cast<std::string>(nb::str(camera.type().attr("__name__"))))
                             .c_str());
  return out;
}

std::pair<int, int> size_of(const std::array<int, 2>& size, const char* what) {
  if (size[0] <= 0 || size[1] <= 0 || size[0] > 16384 || size[1] > 16384)
    fail("{}: width and height must be in 1..16384 pixels, got {}x{}", what, size[0], size[1]);
  return {size[0], size[1]};
}

// A rendered frame and what its stats need.
struct PyFrame {
  Frame frame;
  RenderParams params;
  std::shared_ptr<const Scene> scene;
  size_t triangles = 0;
  double build_ms = 0;
  int threads = 0;
  std::string device, trace_api;
  double wall_ms = 0;  // the library call alone, from inside the binding
};

struct PyRenderer {
  std::shared_ptr<const Scene> scene;
  ComputeDevice device = ComputeDevice::cpu;
  std::unique_ptr<FrameRenderer> renderer;  // keeps the AO rays of the temporal=True frames so far
  int threads = 0;
  std::mutex render_mutex;  // temporal frames, and GPU frames, from several Python threads take turns (the GIL is released)

  PyRenderer(const nb::object& s, const std::string& device_name, int threads_) : scene(scene_of(s).scene), threads(threads_) {
    if (threads < 0) fail("threads: must be 0 (all cores) or more, got {}", threads);
    device = choose_device(device_name);
    nb::gil_scoped_release release;
    const ThreadScope scope(threads);
    renderer = make_frame_renderer(*scene, device);
  }

  std::unique_ptr<PyFrame> render(const std::array<int, 2>& size, const nb::object& camera_arg, std::optional<std::array<double, 2>> gaze,
                                  const std::string& mode, int max_rays, int min_rays, double gamma, double beta, uint64_t seed,
                                  std::optional<Display> display, double ellipse, std::optional<double> ao_distance,
                                  std::optional<double> ambient_constant, bool shadows, bool adaptive, bool denoise, bool temporal,
                                  int temporal_frames, double tolerance) {
    auto out = std::make_unique<PyFrame>();
    RenderParams& p = out->params;
    std::tie(p.width, p.height) = size_of(size, "size");
    p.mode = parse_render_mode(mode);
    p.display = display ? *display : Display{};
    p.foveation = {ellipse, max_rays, min_rays, gamma, beta};
    if (ao_distance) p.ao_distance = static_cast<float>(*ao_distance);
    if (ambient_constant)
      p.ambient_constant = static_cast<float>(*ambient_constant);
    else
      p.ambient_constant.reset();
    p.seed = seed;
    p.shadows = shadows;
    if (gaze) p.gaze_px = glm::dvec2((*gaze)[0], (*gaze)[1]);
    p.reuse.adaptive = adaptive;
    p.reuse.denoise = denoise;
    p.reuse.temporal = temporal;
    p.reuse.temporal_frames = temporal_frames;
    p.reuse.tolerance = tolerance;
    validate(p);
    if (gaze) warn_if_far("gaze", (*gaze)[0], (*gaze)[1], p.width, p.height);
    const Camera camera = resolve_camera(*scene, camera_arg);
    out->scene = scene;
    out->build_ms = renderer->build_ms();
    out->device = to_string(device);
    {
      nb::gil_scoped_release release;
      const ThreadScope scope(threads);
      out->threads = scope.threads();
      const Timer clock;
      // One frame at a time on the GPU's buffers, and on the temporal history on either device
      std::unique_lock<std::mutex> lock(render_mutex, std::defer_lock);
      if (temporal || device == ComputeDevice::cuda) lock.lock();
      out->frame = renderer->render(camera, p);
      out->triangles = renderer->triangles();
      out->trace_api = renderer->trace_api();
      out->wall_ms = clock.ms();
    }
    return out;
  }
};

// The images of frames that Python no longer holds, for the loop to compose later frames into
// (RealtimeLoop::recycle): a fresh image for every frame cost its allocation and page faults,
// composing an 840×525 frame in 1.00 ms instead of 0.62 (medians, bench/paced_loop.py at an 8-ms
// budget, a 2-core AMD EPYC VM)
struct ImageReturns {
  std::mutex mutex;  // (a frame may be released on one Python thread while another renders)
  std::vector<Image> images;
};

struct PyLoopFrame {
  LoopFrame frame;
  double budget_ms = 0;
  std::weak_ptr<ImageReturns> returns;  // its loop's, while the loop lives
  PyLoopFrame() = default;
  PyLoopFrame(const PyLoopFrame&) = delete;
  PyLoopFrame& operator=(const PyLoopFrame&) = delete;
  // Released once nothing holds it: its image views keep the frame alive, so no view sees the image
  // reused
  ~PyLoopFrame() {
    if (const std::shared_ptr<ImageReturns> r = returns.lock()) {
      const std::lock_guard<std::mutex> lock(r->mutex);
      if (r->images.size() < 2) r->images.push_back(std::move(frame.color));  // (the loop keeps two)
    }
  }
};

// The real-time loop of one scene, camera and size on one device (render/realtime.h).
struct PyLoop {
  std::shared_ptr<const Scene> scene;
  std::unique_ptr<FrameRenderer> renderer;
  std::unique_ptr<RealtimeLoop> loop;
  Camera camera;
  int threads = 0;
  std::mutex mutex;  // one frame at a time (the GIL is released while it renders)
  std::shared_ptr<ImageReturns> returns = std::make_shared<ImageReturns>();

  PyLoop(const nb::object& s, const std::array<int, 2>& size, const nb::object& camera_arg, std::optional<Display> display, int max_rays,
         double gamma, double refresh_hz, std::optional<double> frame_budget_ms, bool predict, const std::string& device_name, int threads_,
         uint64_t seed, const std::string& clock, double tolerance, double ellipse, bool keep_history, const nb::object& landing,
         double periphery_share, std::optional<double> margin_ms, bool rays_ahead, double min_scale)
      : scene(scene_of(s).scene), threads(threads_) {
    if (threads < 0) fail("threads: must be 0 (all cores) or more, got {}", threads);
    if (!(refresh_hz >= 1 && refresh_hz <= 1000)) fail("refresh_hz: must be in [1, 1000] Hz, got {}", refresh_hz);
    RenderParams p;
    std::tie(p.width, p.height) = size_of(size, "size");
    p.display = display ? *display : Display{};
    p.foveation.max_rays = max_rays;
    p.foveation.gamma = gamma;
    p.foveation.ellipse_ratio = ellipse;
    p.seed = seed;
    p.reuse.tolerance = tolerance;
    LoopSettings settings;
    settings.budget_ms = frame_budget_ms.value_or(1000.0 / refresh_hz);
    settings.predict = predict;
    settings.keep_history = keep_history;
    settings.periphery_share = periphery_share;
    settings.margin_ms = margin_ms;
    settings.rays_ahead = rays_ahead;
    settings.min_scale = min_scale;
    settings.landing = landing_params_of(landing);
    settings.clock = parse_loop_clock(clock);
    if (settings.clock == LoopClock::model) fail("clock: the model clock is bench latency's; a Loop in Python runs on the wall clock");
    camera = resolve_camera(*scene, camera_arg);
    const ComputeDevice device = choose_device(device_name);
    nb::gil_scoped_release release;
    const ThreadScope scope(threads);
    renderer = make_frame_renderer(*scene, device);
    loop = std::make_unique<RealtimeLoop>(*renderer, *scene, p, settings);
    loop->frame(camera);  // the view's surfaces, before the first frame is asked for
  }

  // A sample at `t` (unset: just after the latest); a repeated or older one is ignored there, a
  // clock that went back taken and noted (gaze_note)
  void push(std::optional<double> t, std::optional<std::array<double, 2>> gaze) {
    if (t && !std::isfinite(*t)) fail("t: must be a finite time in seconds, got {}", *t);
    const std::lock_guard<std::mutex> lock(mutex);
    loop->push_gaze(t ? *t : loop->latest_sample_s().value_or(0.0) + 1e-6,
                    gaze ? std::optional<glm::dvec2>(glm::dvec2((*gaze)[0], (*gaze)[1])) : std::nullopt);
  }

  std::unique_ptr<PyLoopFrame> frame(std::optional<std::array<double, 2>> gaze, std::optional<double> t, const nb::object& camera_arg) {
    if (gaze || t) push(t, gaze);
    if (!camera_arg.is_none()) {
      const Camera moved = resolve_camera(*scene, camera_arg);
      const std::lock_guard<std::mutex> lock(mutex);
      camera = moved;  // the view from now on
    }
    auto out = std::make_unique<PyLoopFrame>();
    out->budget_ms = loop->settings().budget_ms;
    out->returns = returns;
    nb::gil_scoped_release release;
    const ThreadScope scope(threads);
    const std::lock_guard<std::mutex> lock(mutex);
    {
      const std::lock_guard<std::mutex> returned(returns->mutex);
      for (Image& image : returns->images) loop->recycle(std::move(image));
      returns->images.clear();
    }
    out->frame = loop->frame(camera);
    return out;
  }
};

// A simulation and what it was made from.
struct PyVision {
  std::shared_ptr<const Scene> scene;
  std::unique_ptr<Tracer> tracer;
  std::unique_ptr<VisionSimulation> sim;
  SimulateParams params;
  Camera camera;
  int threads = 0;
  // One step at a time: a step changes the simulation's state (the field, the eye, the step count)
  // and its images are read after it, so steps from several Python threads take turns (the GIL is
  // released while one runs)
  std::unique_ptr<std::mutex> mutex = std::make_unique<std::mutex>();
};

struct PyVisionStep {
  nb::ndarray<nb::numpy, float> perceived, color, coc;  // NumPy arrays owning the step's copies
  std::array<float, 2> fixation{};
  double sharp_fraction = 0;
  nb::dict stats;
};

std::unique_ptr<PyVision> make_vision(const PyScene& s, const std::string& eye, const std::array<int, 2>& size, uint64_t seed,
                                      const nb::object& camera, const std::string& device, int threads, int blink_every,
                                      std::optional<double> pupil_mm, double starvation, bool features_every_step) {
  auto v = std::make_unique<PyVision>();
  v->scene = s.scene;
  SimulateParams& p = v->params;
  std::tie(p.width, p.height) = size_of(size, "size");
  const EyeSpec spec = resolve_eye(eye, {pupil_mm, std::nullopt});  // the CLI's rule: pupil_mm, if given, beats the eye's
  p.eye = spec.eye;
  p.impair = spec.impair;
  p.seed = seed;
  p.blink_every = blink_every;
  p.starvation = starvation;
  p.features_every_step = features_every_step;
  if (threads < 0) fail("threads: must be 0 (all cores) or more, got {}", threads);
  v->threads = threads;
  p.cuda = choose_device(device) == ComputeDevice::cuda;
  validate(p);
  v->camera = resolve_camera(*v->scene, camera);
  nb::gil_scoped_release release;
  const ThreadScope scope(threads);
  v->tracer = std::make_unique<Tracer>(*v->scene);
  v->sim = std::make_unique<VisionSimulation>(*v->tracer, *v->scene, p);
  return v;
}

PyVisionStep vision_step(PyVision& v, std::optional<std::array<float, 2>> fixation, const nb::object& camera) {
  if (fixation) warn_if_far("fixation", (*fixation)[0], (*fixation)[1], v.params.width, v.params.height);
  const std::optional<Camera> view = camera.is_none() ? std::nullopt : std::optional<Camera>(resolve_camera(*v.scene, camera));
  StepStats s;
  Image perceived, color;
  std::vector<float> coc;
  {
    nb::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(*v.mutex);
    const ThreadScope scope(v.threads);
    if (view) v.camera = *view;  // the camera stays for the steps after
    std::optional<glm::vec2> fix;
    if (fixation) fix = glm::vec2((*fixation)[0], (*fixation)[1]);
    s = v.sim->step(v.camera, fix);
    perceived = v.sim->perceived();
    color = v.sim->color();
    coc = v.sim->coc_px();
  }
  PyVisionStep r;
  const size_t w = static_cast<size_t>(v.params.width), h = static_cast<size_t>(v.params.height);
  r.perceived = owned_array(std::move(perceived.pixels), {h, w, 3});
  r.color = owned_array(std::move(color.pixels), {h, w, 3});
  r.coc = owned_array(std::move(coc), {h, w});
  r.fixation = {s.focus_px.x, s.focus_px.y};
  r.sharp_fraction = s.sharp_fraction;
  r.stats = nb::cast<nb::dict>(to_python(step_stats_json(s)));
  return r;
}

}  // namespace
}  // namespace foveal::python

using namespace foveal;
using namespace foveal::python;

NB_MODULE(_core, m) {
  m.doc() = "foveal's C++ core: scenes, the foveated AO renderer, the vision simulation, gaze, image comparison";

  // Every library error is one line naming the file and line, or the parameter — here as the
  // keyword argument a Python caller passed (util/error.h: the library names its own fields)
  nb::register_exception_translator([](const std::exception_ptr& p, void*) {
    try {
      std::rethrow_exception(p);
    } catch (const Error& e) {
      static constexpr ParameterName kKeywords[] = {{"pupil_diameter_mm", "pupil_mm"},
                                                    {"ellipse_ratio", "ellipse"},
                                                    {"gaze_px", "gaze"},
                                                    {"fixation_px", "fixation"},
                                                    {"gaze_eye", "eye"},
                                                    {"device cuda", "device='cuda'"},
                                                    {"events", "method"}};
      const std::string what = in_words(e.what(), kKeywords);
      // A file that is not there (the readers say "no such file", or "cannot open" a path that does not exist)
      const size_t cannot = what.find(": cannot open");
      const bool missing = what.find(": no such ") != std::string::npos || what.ends_with(" not found") ||
                           (cannot != std::string::npos && what.find("for writing") == std::string::npos &&
                            !std::filesystem::exists(what.substr(0, cannot)));
      const bool device = what.rfind("device='cuda'", 0) == 0;
      // A message quoting a binary file's bytes keeps them as \xNN escapes, as the command line shows them
      const std::string shown = text::printable(what);
      PyObject* text = PyUnicode_DecodeUTF8(shown.data(), static_cast<Py_ssize_t>(shown.size()), "strict");
      PyErr_SetObject(missing ? PyExc_FileNotFoundError : device ? PyExc_RuntimeError : PyExc_ValueError, text);
      Py_XDECREF(text);
    }
  });

  nb::class_<Display>(m, "Display", "The screen a render fills: physical size, viewing distance and resolution.")
      .def(
          "__init__",
          [](Display* d, double width_cm, double height_cm, double distance_cm, int res_x, int res_y) {
            new (d) Display{width_cm, height_cm, distance_cm, res_x, res_y};
            validate(*d);
          },
          "width_cm"_a = 47.5, "height_cm"_a = 30.0, "distance_cm"_a = 60.0, "res_x"_a = 1680, "res_y"_a = 1050,
          "A display W×H cm seen from D cm, with res_x × res_y pixels (defaults: the papers' 22-inch screen at 60 cm).")
      .def_rw("width_cm", &Display::width_cm)
      .def_rw("height_cm", &Display::height_cm)
      .def_rw("distance_cm", &Display::distance_cm)
      .def_rw("res_x", &Display::res_x)
      .def_rw("res_y", &Display::res_y)
      .def_prop_ro(
          "pixels_per_degree", [](const Display& d) { return pixels_per_degree(d); }, "Display pixels per degree at the screen centre.")
      .def_prop_ro(
          "fov_deg",
          [](const Display& d) {
            return std::array<double, 2>{field_of_view_x_deg(d), field_of_view_y_deg(d)};
          },
          "Horizontal and vertical field of view, degrees.")
      .def("__repr__", [](const Display& d) {
        return fmt::format("Display(width_cm={}, height_cm={}, distance_cm={}, res_x={}, res_y={})", d.width_cm, d.height_cm, d.distance_cm,
                           d.res_x, d.res_y);
      });

  nb::class_<Camera>(m, "Camera", "A pinhole camera: position, point looked at, up vector, vertical field of view.")
      .def(
          "__init__",
          [](Camera* c, Vec3 eye, Vec3 look, Vec3 up, float fov, const std::string& name) {
            new (c) Camera{name, vec(eye), vec(look), vec(up), fov};
            if (glm::length(c->look - c->eye) == 0) fail("Camera: eye and look must differ");
            if (glm::length(glm::cross(c->look - c->eye, c->up)) == 0) fail("Camera: up must not be parallel to the view direction");
            if (!(fov > 0 && fov < 180)) fail("Camera: fov must be in (0, 180) degrees, got {}", fov);
          },
          "eye"_a, "look"_a, "up"_a = Vec3{0, 1, 0}, "fov"_a = 45.0f, "name"_a = "python",
          "A camera at `eye` looking at `look` (scene units), `fov` the vertical field of view in degrees.")
      .def_prop_ro("name", [](const Camera& c) { return c.name; })
      .def_prop_ro("eye", [](const Camera& c) { return tuple(c.eye); })
      .def_prop_ro("look", [](const Camera& c) { return tuple(c.look); })
      .def_prop_ro("up", [](const Camera& c) { return tuple(c.up); })
      .def_prop_ro("fov", [](const Camera& c) { return c.fov_deg; })
      .def(
          "orbit", [](const Camera& c, double degrees) { return orbit_camera(c, degrees); }, "degrees"_a,
          "This camera moved `degrees` around its look point about its up axis (as replay --orbit).")
      .def("__repr__", [](const Camera& c) {
        return fmt::format("Camera(eye=({}, {}, {}), look=({}, {}, {}), fov={}, name='{}')", c.eye.x, c.eye.y, c.eye.z, c.look.x, c.look.y,
                           c.look.z, c.fov_deg, c.name);
      });

  nb::class_<PyScene>(m, "Scene", "A scene: a mesh file, a scene .json, or builtin:box|sphere-plane|plane.")
      .def(
          "__init__", [](PyScene* s, const std::filesystem::path& path) { new (s) PyScene(PyScene::load(path)); }, "path_or_builtin"_a,
          "Load a mesh (OBJ, PLY, glTF, … through Assimp), a scene .json or a built-in scene.")
      .def_prop_ro("source", [](const PyScene& s) { return s.scene->source; })
      .def_prop_ro(
          "triangles", [](const PyScene& s) { return s.scene->triangles.size(); }, "Triangles loaded.")
      .def_prop_ro(
          "cameras", [](const PyScene& s) { return s.scene->cameras; }, "The scene's named cameras.")
      .def(
          "camera", [](const PyScene& s, const std::string& name) { return find_camera(*s.scene, name); }, "name"_a,
          "The named camera (ValueError listing the names when there is none).")
      .def(
          "default_camera", [](const PyScene& s) { return default_camera(*s.scene); }, "A camera framing the whole scene.")
      .def("__repr__",
           [](const PyScene& s) { return fmt::format("Scene('{}', {} triangles)", s.scene->source, s.scene->triangles.size()); });

  nb::class_<PyFrame>(m, "Frame", "A rendered frame. Its arrays are views of the frame's own buffers.")
      .def_prop_ro(
          "image",
          [](PyFrame& f) {
            const Image& c = f.frame.color;
            return nb::ndarray<nb::numpy, float>(const_cast<float*>(c.pixels.data()),
                                                 {size_t(c.height), size_t(c.width), size_t(c.channels)}, nb::find(&f));
          },
          "The shaded image: float32 H×W×3, linear RGB, a view (no copy) valid while the frame lives.")
      .def(
          "aov",
          [](PyFrame& f, const std::string& name) {
            Image img = aov_image(f.frame, name);
            const size_t h = img.height, w = img.width, c = img.channels;
            if (c == 1) return owned_array(std::move(img.pixels), {h, w});
            return owned_array(std::move(img.pixels), {h, w, c});
          },
          "name"_a,
          "A float buffer by the CLI's AOV name: ao, depth, position, normal, albedo, budget, quality, blend, eccentricity "
          "(H×W or H×W×3; NaN where nothing was hit).")
      .def_prop_ro(
          "stats",
          [](const PyFrame& f) {
            return nb::cast<nb::dict>(
                to_python(frame_stats_json(f.frame, f.params, *f.scene, f.triangles, f.build_ms, f.threads, f.device, f.trace_api)));
          },
          "Timings and ray counts: the same fields as `foveal render --stats`.")
      .def_prop_ro(
          "gaze",
          [](const PyFrame& f) {
            return std::array<double, 2>{f.frame.gaze_px.x, f.frame.gaze_px.y};
          },
          "The gaze point in render pixels.")
      .def_prop_ro("width", [](const PyFrame& f) { return f.frame.color.width; })
      .def_prop_ro("height", [](const PyFrame& f) { return f.frame.color.height; })
      .def_prop_ro(
          "library_ms", [](const PyFrame& f) { return f.wall_ms; },
          "Wall time of the library's render call alone, ms (for measuring the binding's own overhead).")
      .def(
          "save", [](const PyFrame& f, const std::filesystem::path& path) { save_image(f.frame.color, path.string()); }, "path"_a,
          "Write the image as the CLI does (.png sRGB; .pfm/.exr linear floats).");

  nb::class_<PyRenderer>(m, "Renderer", "The foveated-AO renderer of one scene on one device.")
      .def(nb::init<const nb::object&, const std::string&, int>(), "scene"_a, "device"_a = "auto", "threads"_a = 0,
           "Build the BVH of `scene` (a Scene, or a path or builtin:NAME, loaded then) on `device` (auto: cuda when a usable NVIDIA GPU is "
           "present, else cpu); "
           "`threads` = 0 uses all cores.")
      .def("render", &PyRenderer::render, "size"_a = std::array<int, 2>{840, 525}, "camera"_a = nb::none(), "gaze"_a = nb::none(),
           "mode"_a = "foveated", "max_rays"_a = 400, "min_rays"_a = 0, "gamma"_a = 2.0, "beta"_a = 0.0, "seed"_a = 1,
           "display"_a = nb::none(), "ellipse"_a = 1.538, "ao_distance"_a = nb::none(), "ambient_constant"_a = 1.0, "shadows"_a = false,
           "adaptive"_a = false, "denoise"_a = false, "temporal"_a = false, "temporal_frames"_a = 4,
           "tolerance"_a = foveal::AoReuseParams{}.tolerance,
           "Render one frame. `gaze` (x, y) in render pixels, origin top-left (default: the centre); mode 'foveated' "
           "(the AO budget follows the gaze) or 'full' (max_rays everywhere: the reference); `camera` a Camera, a "
           "camera name or None (the scene's first); `ambient_constant` None = the fovea's mean visibility. "
           "More quality per ray (the CLI's --adaptive, --denoise, --temporal, --temporal-frames, --tolerance; on the CPU "
           "and the GPU): `temporal` builds on the AO rays of this Renderer's earlier temporal frames, reprojected to the "
           "new camera (reset_history() starts afresh). The GIL is released while rendering.")
      .def(
          "reset_history",
          [](PyRenderer& r) {
            nb::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(r.render_mutex);
            r.renderer->reset_history();
          },
          "Forget the AO rays kept for temporal=True: the next temporal frame is the paper's frame.")
      .def_prop_ro("device", [](const PyRenderer& r) { return std::string(to_string(r.device)); })
      .def_prop_ro("device_description", [](const PyRenderer& r) { return r.renderer->describe(); });

  nb::class_<PyLoopFrame>(m, "LoopFrame", "One frame of a Loop: the image and the state of the fovea when it was made.")
      .def_prop_ro(
          "image",
          [](PyLoopFrame& f) {
            const Image& c = f.frame.color;
            return nb::ndarray<nb::numpy, float>(const_cast<float*>(c.pixels.data()),
                                                 {size_t(c.height), size_t(c.width), size_t(c.channels)}, nb::find(&f));
          },
          "The image: float32 H×W×3, linear RGB, at the loop's render size (smaller than asked where the base shading did not fit "
          "the budget: see Loop.scale), a view of the frame's buffer, valid while the frame lives; once neither the frame nor a view "
          "of it is held, the buffer goes back to the loop for a later frame.")
      .def_prop_ro(
          "fovea", [](const PyLoopFrame& f) { return std::string(f.frame.fovea_done ? "converged" : "refining"); },
          "'converged' once every pixel of the fovea (q = 1 around where it was placed) has its n_max rays, else 'refining'.")
      .def_prop_ro(
          "fovea_converged", [](const PyLoopFrame& f) { return f.frame.fovea_converged; }, "The fovea's converged fraction, 0–1.")
      .def_prop_ro(
          "gaze",
          [](const PyLoopFrame& f) {
            return std::array<double, 2>{f.frame.gaze_px.x, f.frame.gaze_px.y};
          },
          "Where the fovea was placed, render pixels: the latest gaze, or a saccade's predicted landing.")
      .def_prop_ro(
          "measured_gaze",
          [](const PyLoopFrame& f) {
            return std::array<double, 2>{f.frame.measured_px.x, f.frame.measured_px.y};
          },
          "The latest measured gaze, render pixels.")
      .def_prop_ro(
          "predicted", [](const PyLoopFrame& f) { return f.frame.predicted; }, "The fovea was placed at a predicted landing.")
      .def_prop_ro(
          "in_flight", [](const PyLoopFrame& f) { return f.frame.in_flight; }, "A saccade was under way at the latest sample.")
      .def_prop_ro(
          "rays", [](const PyLoopFrame& f) { return f.frame.rays; }, "AO rays traced for this frame.")
      .def_prop_ro(
          "ms", [](const PyLoopFrame& f) { return f.frame.ms; }, "Wall time of the frame, ms.")
      .def_prop_ro(
          "late", [](const PyLoopFrame& f) { return f.frame.late; }, "The frame took longer than its budget.")
      .def_prop_ro(
          "budget_ms", [](const PyLoopFrame& f) { return f.budget_ms; }, "The frame budget, ms.")
      .def_prop_ro(
          "new_view", [](const PyLoopFrame& f) { return f.frame.new_view; },
          "The camera had moved, or the size it had before moving came back: the view's surfaces were traced; or a still "
          "view's size was lowered (`lowered`).")
      .def_prop_ro(
          "scale", [](const PyLoopFrame& f) { return f.frame.scale; },
          "The image's size as a share of the size asked for (1, or less where the loop lowered it: Loop.note says why; "
          "Loop.scale may already be the next frame's).")
      .def_prop_ro(
          "lowered", [](const PyLoopFrame& f) { return f.frame.lowered; },
          "A still view's size was lowered for its fixed part (Loop.note says why), taken from the view at hand: each smaller "
          "pixel one of the larger pixels nearest it, the one with the most rays, with its rays so far; no surface traced.")
      .def_prop_ro(
          "rebuilding", [](const PyLoopFrame& f) { return f.frame.rebuilding; },
          "Part of this frame built, a few rows at a time, the view at another size (the view at hand is shown meanwhile): a "
          "larger one (the size a camera at rest gets back, or a still view's once its fixed part fits again), or a still view's "
          "lower size, taken from the view at hand (`lowered` once it is shown).")
      .def_prop_ro(
          "kept_pixels", [](const PyLoopFrame& f) { return f.frame.kept_pixels; },
          "A new view: the pixels that kept AO rays from the view before (0 with keep_history=False).")
      .def_prop_ro(
          "chunks_left_behind", [](const PyLoopFrame& f) { return f.frame.chunks_left_behind; },
          "Wall clock: chunks of this frame's rays (normally 10–40 µs each) left to threads the machine had "
          "paused, their rays dropped and cast again later, rather than waited for (docs/realtime.md).")
      .def_prop_ro(
          "left_behind_ms", [](const PyLoopFrame& f) { return f.frame.left_behind_ms; },
          "Where the frame before left chunks behind: how long after its rays stopped the last of them ended, how much later "
          "it would have ended had it waited for them (NaN where it left none).")
      .def_prop_ro(
          "estimate_deferred", [](const PyLoopFrame& f) { return f.frame.estimate_deferred; },
          "Wall clock: the estimate of the pixels without rays was due, but this frame had no room for it before its rays' "
          "deadline (most often one that evaluated the foveation maps at every pixel), and it waits for a frame that has: "
          "meanwhile those pixels show the estimate before (docs/realtime.md).")
      .def_prop_ro("index", [](const PyLoopFrame& f) { return f.frame.index; });

  nb::class_<PyLoop>(m, "Loop",
                     "Gaze-contingent rendering in real time: frame() returns within the frame budget an image whose fovea "
                     "is refined first (docs/realtime.md).")
      .def(nb::init<const nb::object&, const std::array<int, 2>&, const nb::object&, std::optional<Display>, int, double, double,
                    std::optional<double>, bool, const std::string&, int, uint64_t, const std::string&, double, double, bool,
                    const nb::object&, double, std::optional<double>, bool, double>(),
           "scene"_a, "size"_a = std::array<int, 2>{840, 525}, "camera"_a = nb::none(), "display"_a = nb::none(), "max_rays"_a = 400,
           "gamma"_a = 2.0, "refresh_hz"_a = 60.0, "frame_budget_ms"_a = nb::none(), "predict"_a = true, "device"_a = "auto",
           "threads"_a = 0, "seed"_a = 1, "clock"_a = "wall", "tolerance"_a = foveal::AoReuseParams{}.tolerance, "ellipse"_a = 1.538,
           "keep_history"_a = true, "landing"_a.none() = nb::none(), "periphery_share"_a = kDefaultPeripheryShare,
           "margin_ms"_a.none() = nb::none(), "rays_ahead"_a = true, "min_scale"_a = kDefaultMinScale,
           "A loop for a view of `scene` (a Scene, or a path or builtin:NAME, loaded then; traced here, once; frame(camera=…) "
           "moves it). `frame_budget_ms` (default: one refresh at "
           "`refresh_hz`) is what each frame() may take; `predict` places the fovea at a saccade's predicted landing while it "
           "flies; `display` the screen the image fills (default: the papers' 47.5×30 cm, 1680×1050 at 60 cm); `tolerance` the "
           "periphery's τ(E) scale (as render --tolerance); `keep_history` lets a moved camera keep the AO of the surfaces it "
           "still sees (else it starts afresh); `landing` the saccade landing predictor's parameters: a dict by name (as "
           "foveal.gaze.predict_landings's keywords: onset_deg_s, …) or the text of --landing ('onset_deg_s=60,skew=1.2'); "
           "`periphery_share` the share of the budget after which a frame casts no more rays for the periphery (the fovea's go "
           "on to the deadline; 1: the periphery's too); `margin_ms` the least time each frame keeps free for the machine's "
           "pauses (None: 2 ms, or a quarter of a shorter budget; more after frames that ended late, up to a quarter of the "
           "budget; a budget set later keeps a margin given within half of it); `rays_ahead`: once every pixel has its n(E), "
           "the frames' spare time (up to half of each budget) takes every pixel on to n_max, nearest the gaze first, so that "
           "where the eye lands next its fovea finds those rays (False: a converged view casts nothing); `min_scale` the "
           "smallest size the loop may render at where its base shading does not fit the budget, a share of `size` in (0, 1] "
           "(1: the stimulus keeps its resolution throughout, and such frames come late instead, `note` saying so).")
      .def("push", &PyLoop::push, "t"_a, "gaze"_a,
           "A tracker sample: its time in seconds (any clock, increasing; None: just after the latest sample) and the gaze "
           "(x, y) in render pixels, or None (or NaN, as many trackers write it) when the tracker lost the eye. Push every sample a fast "
           "tracker delivers "
           "between frames: the saccade predictor needs them. A repeated time, or one up to 0.5 s before the latest, is "
           "ignored (a duplicate, samples out of order); one further back is a clock that restarted: the sample is taken, "
           "the predictor starts afresh, and gaze_note says so.")
      .def("frame", &PyLoop::frame, "gaze"_a = nb::none(), "t"_a = nb::none(), "camera"_a = nb::none(),
           "The next frame, within the budget: `gaze` (x, y) and `t` (seconds), when given, are pushed first; `camera` (a "
           "Camera or a camera name of the scene), when given, is the view from this frame on. The GIL is released while it "
           "renders on the worker threads.")
      .def_prop_ro(
          "scale", [](const PyLoop& l) { return l.loop->scale(); },
          "Render size / the size asked for (1 unless the base shading did not fit).")
      .def_prop_ro(
          "note", [](const PyLoop& l) { return l.loop->note(); },
          "Why the resolution was lowered, or why it could not be lowered further (min_scale: frames come late); '' if neither.")
      .def_prop_ro(
          "gaze_note", [](const PyLoop& l) { return l.loop->gaze_note(); },
          "What the samples pushed leave the landing predictor ('' if nothing to say): with prediction on, that saccade "
          "landings cannot be predicted from them — they come under 20 Hz, most often times in milliseconds where seconds are "
          "asked for — or only too late to gain much (under 90 Hz); and that their clock went back (a trial clock that "
          "restarts).")
      .def_prop_ro(
          "gaze_sample_hz", [](const PyLoop& l) { return l.loop->gaze_sample_hz(); },
          "The rate the valid samples pushed come at: 1 / the median of the latest 16 intervals, as gaze_note judges it "
          "(0 before two have come).")
      .def_prop_ro(
          "size",
          [](const PyLoop& l) {
            return std::array<int, 2>{l.loop->params().width, l.loop->params().height};
          },
          "The render size in use.")
      .def_prop_rw(
          "budget_ms", [](const PyLoop& l) { return l.loop->settings().budget_ms; },
          [](PyLoop& l, double ms) {
            const std::lock_guard<std::mutex> lock(l.mutex);
            l.loop->set_budget_ms(ms);
          },
          "Each frame's budget, ms; settable, so that an experiment leaves the loop what its own per-frame work (drawing, "
          "flipping) does not take of the refresh.")
      .def_prop_ro(
          "margin_ms", [](const PyLoop& l) { return loop_margin_ms(l.loop->settings()); },
          "The least time each frame keeps free for the machine's pauses, ms: margin_ms as given (within half of a budget "
          "set later), else 2 ms or a quarter of a shorter budget.")
      .def_prop_ro(
          "periphery_share", [](const PyLoop& l) { return l.loop->settings().periphery_share; },
          "The share of the budget after which a frame casts no more rays for the periphery.")
      .def_prop_ro(
          "min_scale", [](const PyLoop& l) { return l.loop->settings().min_scale; },
          "The smallest size the loop may render at, a share of the size asked for (min_scale).")
      .def_prop_ro(
          "rays_ahead", [](const PyLoop& l) { return l.loop->settings().rays_ahead; },
          "Whether a converged view's spare time takes every pixel on to n_max (rays_ahead).")
      .def_prop_ro(
          "device", [](const PyLoop& l) { return l.renderer->describe(); }, "Where the loop renders.");

  nb::class_<PyVisionStep>(m, "VisionStep", "One step of the vision simulation (arrays are the step's own copies).")
      .def_prop_ro(
          "perceived", [](const PyVisionStep& s) { return s.perceived; }, nb::rv_policy::automatic,
          "What the eye perceives: float32 H×W×3, linear RGB.")
      .def_prop_ro(
          "color", [](const PyVisionStep& s) { return s.color; }, nb::rv_policy::automatic,
          "The sharp ray-cast image: float32 H×W×3, linear RGB.")
      .def_prop_ro(
          "coc", [](const PyVisionStep& s) { return s.coc; }, nb::rv_policy::automatic,
          "Per-pixel circle-of-confusion diameter used for the blur, pixels (H×W).")
      .def_ro("fixation", &PyVisionStep::fixation, "The fixation of this step, render pixels.")
      .def_ro("sharp_fraction", &PyVisionStep::sharp_fraction, "Share of pixels remembered sharp.")
      .def_ro("stats", &PyVisionStep::stats,
              "The step's record, as in `simulate --stats`: focus_px, depth, accommodation, blink, corners, stage times (ms).");

  nb::class_<PyVision>(m, "VisionSimulation", "The second paper's simulation of human vision over time.")
      .def(
          "__init__",
          [](PyVision* v, const nb::object& s, const std::string& eye, const std::array<int, 2>& size, uint64_t seed,
             const nb::object& camera, const std::string& device, int threads, int blink_every, std::optional<double> pupil_mm,
             double starvation, bool features_every_step) {
            new (v) PyVision(std::move(*make_vision(scene_of(s), eye, size, seed, camera, device, threads, blink_every, pupil_mm,
                                                    starvation, features_every_step)));
          },
          "scene"_a, "eye"_a = "healthy", "size"_a = std::array<int, 2>{1024, 768}, "seed"_a = 1, "camera"_a = nb::none(),
          "device"_a = "auto", "threads"_a = 0, "blink_every"_a = 0, "pupil_mm"_a = nb::none(), "starvation"_a = 0.015,
          "features_every_step"_a = false,
          "A simulation of `eye` (the CLI's --eye: presets joined with '+', e.g. 'myopia:-2+cvd:deutan:0.6', or a profile "
          ".json) looking at `scene` (a Scene, or a path or builtin:NAME, loaded then) through `camera`. `pupil_mm` (the CLI's --pupil), "
          "when given, overrides the eye's pupil "
          "(a profile's pupil_mm, else 3.5 mm).")
      .def("step", &vision_step, "fixation"_a = nb::none(), "camera"_a = nb::none(),
           "One step: the next fixation (simulated saccade, or `fixation` (x, y) in render pixels from real gaze), "
           "accommodation, the sharpness field, the blur and the impairments. Returns a VisionStep.")
      .def(
          "blink",
          [](PyVision& v) {
            nb::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(*v.mutex);
            v.sim->blink_before_next_step();
          },
          "The eye blinks before the next step (the field forgets).")
      .def_prop_ro("on_gpu", [](const PyVision& v) { return v.sim->on_gpu(); })
      .def_prop_ro(
          "optics", [](const PyVision& v) { return nb::cast<nb::dict>(to_python(optics_json(v.params.eye))); },
          "The eye's optics as resolved (as `simulate --stats` writes them): preset, pupil_mm, image_distance_mm, "
          "refraction_d, cylinder_d, axis_deg, age_years, glaucoma.");

  m.def(
      "_compare",
      [](const nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>& a,
         const nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>& b,
         std::optional<nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>> b2, std::optional<std::array<double, 2>> gaze,
         std::optional<Display> display, double ellipse, const std::string& ssim_border) {
        const Image ia = image_from(a), ib = image_from(b);
        std::optional<Image> ib2;
        if (b2) ib2 = image_from(*b2);
        const Display d = display ? *display : Display{};  // the command line's default, 47.5,30,60,1680,1050
        if (!(ellipse > 0) || !std::isfinite(ellipse)) fail("ellipse: must be a finite number > 0, got {}", ellipse);
        FoveationParams params;
        params.ellipse_ratio = ellipse;
        const glm::dvec2 g = gaze ? glm::dvec2((*gaze)[0], (*gaze)[1]) : glm::dvec2(ia.width * 0.5, ia.height * 0.5);
        const SsimBorder border = parse_ssim_border(ssim_border);
        nlohmann::json j;
        {
          nb::gil_scoped_release release;
          const Comparison c = compare_images(ia, ib, ib2 ? &*ib2 : nullptr, d, g, params, default_bands(), border);
          j = comparison_json(c, d);
          j["ssim_border"] = to_string(border);
        }
        return to_python(j);
      },
      "a"_a, "b"_a, "b2"_a = nb::none(), "gaze"_a = nb::none(), "display"_a = nb::none(), "ellipse"_a = 1.538, "ssim_border"_a = "reflect");

  m.def(
      "load_image",
      [](const std::filesystem::path& path) {
        Image img = load_image(path.string());
        const size_t h = img.height, w = img.width, c = img.channels;
        return owned_array(std::move(img.pixels), {h, w, c});
      },
      "path"_a, "Read an image as the CLI does: PNG/JPEG decoded from sRGB to linear, PFM/EXR as stored (float32 H×W×C).");
  m.def(
      "save_image",
      [](const nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>& a, const std::filesystem::path& path) {
        save_image(image_from(a), path.string());
      },
      "image"_a, "path"_a, "Write a linear float32 H×W×3 image as the CLI does (.png sRGB; .pfm/.exr exact).");
  m.def(
      "_linear_to_srgb",
      [](const nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>& a,
         nb::ndarray<float, nb::ndim<3>, nb::c_contig, nb::device::cpu> out, float low, float high, bool bottom_up) {
        // (shapes checked by foveal.linear_to_srgb; the conversion on foveal's threads, without the GIL)
        const float* in = a.data();
        float* to = out.data();
        const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1)), c = static_cast<int>(a.shape(2));
        nb::gil_scoped_release release;
        linear_to_srgb(in, to, w, h, c, low, high, bottom_up);
      },
      "image"_a, "out"_a, "low"_a, "high"_a, "bottom_up"_a);
  m.def(
      "stalls",
      [](double duration_s, int threads, double threshold_ms, double chunk_us, double margin_ms) {
        validate_stall_margin(margin_ms);
        StallProbeParams p;
        p.duration_s = duration_s;
        p.threads = threads;
        p.threshold_ms = threshold_ms;
        p.chunk_us = chunk_us;
        validate(p);
        nlohmann::json j;
        {
          nb::gil_scoped_release release;
          j = stalls_json(probe_stalls(p), threshold_ms, margin_ms);
        }
        return to_python(j);
      },
      "duration_s"_a = 10.0, "threads"_a = 0, "threshold_ms"_a = 1.0, "chunk_us"_a = 100.0, "margin_ms"_a = kDefaultMarginMs,
      "How often this machine pauses a working thread, off its CPU or on it (`foveal bench stalls`; docs/realtime.md): the dict "
      "of its --json.");
  nb::class_<MachineThreads>(m, "MachineSnapshot",
                             "Every thread's time on a CPU on this machine at one moment (Linux /proc; empty elsewhere): "
                             "foveal.busiest_others(snapshot) names what else ran since.")
      .def(
          "__len__", [](const MachineThreads& t) { return t.size(); }, "How many processes were read.");
  m.def(
      "machine_snapshot",
      []() {
        nb::gil_scoped_release release;
        return read_machine_threads();
      },
      "Every thread's time on a CPU now, to name with busiest_others() what else ran during a session (docs/realtime.md).");
  m.def(
      "busiest_others",
      [](const MachineThreads& since, int most) {
        if (most < 1) fail("most: must be 1 or more, got {}", most);
        std::vector<BusyProcess> others;
        {
          nb::gil_scoped_release release;
          others = busiest_others(since, read_machine_threads(), current_process_id(), static_cast<size_t>(most));
        }
        return to_python(others_json(others));
      },
      "since"_a, "most"_a = static_cast<int>(kBusiestOthers),
      "The other processes that ran on this machine since a machine_snapshot(), the busiest first: a list of dicts with pid, "
      "name, kernel (a kernel thread), cpu_ms and slices (turns on a CPU) — what takes a real-time loop's cores.");
  m.def(
      "_bench_latency",
      [](const nb::object& scene, const nb::list& recordings, const nb::object& camera_arg, const std::array<int, 2>& size,
         std::optional<Display> display, double start_s, double duration_s, double refresh_hz, std::optional<double> frame_budget_ms,
         std::optional<double> latency_ms, std::optional<double> margin_ms, const std::string& clock,
         std::optional<double> model_rays_per_ms, std::optional<double> model_fixed_ms, const std::vector<std::string>& loops,
         double min_amplitude_deg, int max_rays, double tolerance, uint64_t seed, const std::string& device_name, int threads,
         bool progress, const std::string& timeline, int timeline_saccade, const nb::object& landing, std::optional<double> periphery_share,
         bool rays_ahead, std::optional<double> min_scale) {
        // `bench latency` (apps/bench_latency.cpp) on recordings foveal.gaze hands over as columns
        const PyScene s = scene_of(scene);
        LatencyParams p;
        std::tie(p.render.width, p.render.height) = size_of(size, "size");
        p.render.display = display ? *display : Display{};
        p.render.foveation.max_rays = max_rays;
        p.render.seed = seed;
        p.render.reuse.tolerance = tolerance;
        p.refresh_hz = refresh_hz;
        p.budget_ms = frame_budget_ms;
        p.tracker_latency_ms = latency_ms;
        p.margin_ms = margin_ms;
        p.rays_ahead = rays_ahead;
        p.periphery_share = periphery_share.value_or(kDefaultPeripheryShare);
        p.min_scale = min_scale.value_or(kDefaultMinScale);
        p.clock = parse_loop_clock(clock);
        p.model_rays_per_ms = model_rays_per_ms;
        p.model_fixed_ms = model_fixed_ms;
        p.start_s = start_s;
        p.duration_s = duration_s;
        p.min_amplitude_deg = min_amplitude_deg;
        p.loops = loops;
        p.landing = landing_params_of(landing);
        if (threads < 0) fail("threads: must be 0 (all cores) or more, got {}", threads);
        if (timeline_saccade < 0) fail("timeline_saccade: must be 0 or more, got {}", timeline_saccade);
        if (!timeline.empty()) {
          p.timeline_saccade = static_cast<size_t>(timeline_saccade);
          try {
            check_output_file(timeline, plot_extensions());
          } catch (const Error& e) {
            fail("timeline: {}", e.what());
          }
        }
        validate(p);
        if (recordings.size() == 0) fail("recordings: give at least one");
        std::vector<Recording> recs;
        for (const nb::handle item : recordings) {
          const nb::tuple pair = nb::cast<nb::tuple>(item);
          Recording r = recording_from(nb::cast<nb::dict>(pair[1]));
          r.source = nb::cast<std::string>(pair[0]);
          recs.push_back(std::move(r));
        }
        const Camera camera = resolve_camera(*s.scene, camera_arg);
        const ComputeDevice device = choose_device(device_name);
        nlohmann::json j;
        {
          nb::gil_scoped_release release;
          const ThreadScope scope(threads);
          LatencyReport report =
              bench_latency(*s.scene, s.scene->source, camera, device, scope.threads(), recs, p, [progress](const std::string& line) {
                if (!progress) return;
                fmt::print("{}\n", line);
                std::fflush(stdout);
              });
          report.json["markdown"] = report.markdown;
          if (!timeline.empty()) {
            write_latency_timeline(report, min_amplitude_deg, timeline);
            report.json["timeline_note"] = latency_timeline_note(report, static_cast<size_t>(timeline_saccade), "timeline_saccade=");
          }
          j = std::move(report.json);
        }
        return to_python(j);
      },
      "scene"_a, "recordings"_a, "camera"_a.none(), "size"_a, "display"_a.none(), "start_s"_a, "duration_s"_a, "refresh_hz"_a,
      "frame_budget_ms"_a.none(), "latency_ms"_a.none(), "margin_ms"_a.none(), "clock"_a, "model_rays_per_ms"_a.none(),
      "model_fixed_ms"_a.none(), "loops"_a, "min_amplitude_deg"_a, "max_rays"_a, "tolerance"_a, "seed"_a, "device"_a, "threads"_a,
      "progress"_a, "timeline"_a, "timeline_saccade"_a, "landing"_a.none(), "periphery_share"_a.none(), "rays_ahead"_a,
      "min_scale"_a.none());
  m.def(
      "device_available", [] { return availability().usable; }, "Whether a usable NVIDIA GPU answered.");
  m.def(
      "device_description", [] { return availability().describe(); }, "The GPU, or why there is none.");
  m.def(
      "choose_device", [](const std::string& name) { return std::string(to_string(choose_device(name))); }, "name"_a,
      "The device `name` (auto, cpu or cuda) renders on, 'cpu' or 'cuda', as every device= argument chooses it: "
      "ValueError for an unknown name, RuntimeError for cuda where no usable GPU answered.");

  bind_gaze(m);
  bind_perceive(m);
}
