// foveal/ui/window.cpp — see window.h. The only file that talks to GLFW, OpenGL and Dear ImGui.
#include "foveal/ui/window.h"

#include "foveal/io/image_io.h"
#include "foveal/ui/navigation.h"

#include "foveal/util/error.h"
#include "foveal/util/stats.h"
#include "foveal/util/timer.h"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/core.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <deque>
#include <filesystem>
#include <thread>

namespace foveal {

namespace {

std::string glfw_error;  // the last message of GLFW's error callback

// Numbered free path beside the requested one: name.png, name_1.png, name_2.png, …
std::string free_path(const std::string& path) {
  namespace fs = std::filesystem;
  if (!fs::exists(path)) return path;
  const fs::path p(path);
  for (int i = 1;; ++i) {
    fs::path candidate = p.parent_path() / fmt::format("{}_{}{}", p.stem().string(), i, p.extension().string());
    if (!fs::exists(candidate)) return candidate.string();
  }
}

const char* const kEyePresets[] = {"healthy",     "glaucoma:0.5",  "glaucoma:0.8",    "myopia:-3",
                                   "hyperopia:2", "presbyopia:60", "astigmatism:2@45"};

// The window: GLFW and OpenGL, Dear ImGui's panel, the session's image as a texture. One frame
// per frame() call, at most about 60 a second.
class ViewerWindow {
 public:
  ViewerWindow(ViewSession& session, WindowOptions options)
      : session_(session), options_(std::move(options)), overlays_(options_.overlays), home_(session.camera()), edit_(session.settings()) {
    nav_.speed = std::max(1e-3f, glm::length(home_.look - home_.eye) * 0.5f);
    std::snprintf(eye_text_, sizeof eye_text_, "%s", edit_.eye.c_str());
  }
  ~ViewerWindow() {
    if (texture_) glDeleteTextures(1, &texture_);
    if (imgui_) {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
    if (window_) glfwDestroyWindow(window_);
    if (glfw_) glfwTerminate();
  }
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;

  int run() {
    open_window();  // here, not in the constructor: the destructor closes what a failed opening left
    while (!glfwWindowShouldClose(window_))
      if (!frame()) break;
    return 0;
  }

 private:
  static constexpr int kPanelW = 340;

  // Where the image sits: letterboxed in the area left of the panel.
  struct Layout {
    int fb_w = 0, fb_h = 0;
    float iw = 0, ih = 0, scale = 1;
    ImVec2 p0, p1;
  };

  void open_window() {
    glfwSetErrorCallback([](int, const char* message) { glfw_error = message ? message : "unknown GLFW error"; });
    if (!glfwInit()) fail("cannot open a window: {} (`foveal view` needs a display: set DISPLAY, or run it under xvfb-run)", glfw_error);
    glfw_ = true;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
    image_w_ = session_.settings().render.width * session_.panes();  // the window fits the first mode
    image_h_ = session_.settings().render.height;
    int win_w = image_w_ + (options_.panel ? kPanelW : 0), win_h = std::max(image_h_, options_.panel ? 640 : 0);
    if (const GLFWvidmode* mode = glfwGetVideoMode(glfwGetPrimaryMonitor())) {
      win_w = std::min(win_w, mode->width);
      win_h = std::min(win_h, mode->height - 60);
      session_.set_display_refresh_hz(mode->refreshRate);
    }
    window_ = glfwCreateWindow(win_w, win_h, options_.title.c_str(), nullptr, nullptr);
    if (!window_) fail("cannot open a window: {} (needs OpenGL 3.0; under xvfb-run Mesa's software renderer provides it)", glfw_error);
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    imgui_ = true;
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the user's folder
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 130");
    glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  }

  // One frame; false when the window is done (a script's last frame was written).
  bool frame() {
    glfwPollEvents();
    const double dt_ms = time_frame();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    const Layout at = layout();
    handle_input(at, dt_ms);
    if (options_.panel) draw_panel();
    apply_settings();
    draw_image(at);
    if (finishing_) {
      write_finished(at);
      return false;
    }
    glfwSwapBuffers(window_);
    ++frames_;
    if (options_.frames > 0 && frames_ >= options_.frames) {
      // Scripts: wait for the current inputs' last stage, show it once more, then write it
      if (!session_.wait_until_converged(options_.converge_timeout_s, overlays_))
        fail("the render did not finish within {:.0f} s", options_.converge_timeout_s);
      if (session_.status().stage.starts_with("error")) fail("{}", session_.status().stage.substr(7));
      finishing_ = true;
      frame_clock_.reset();  // the wait is not a frame
      return true;
    }
    // About 60 frames a second at most: the renderer gets the rest of the CPU
    const double spent = frame_clock_.ms();
    if (spent < 16) std::this_thread::sleep_for(std::chrono::microseconds(static_cast<int>((16 - spent) * 1000)));
    return true;
  }

  // The time since the last frame, kept for the panel (the last 60) and the screenshot (all).
  double time_frame() {
    const double dt_ms = frame_clock_.ms();
    frame_clock_.reset();
    if (frames_ > 0) {
      frame_ms_.push_back(dt_ms);
      all_ms_.push_back(dt_ms);
      if (frame_ms_.size() > 60) frame_ms_.pop_front();
    }
    median_frame_ms_ = frame_ms_.empty() ? 0.0 : median(std::vector<double>(frame_ms_.begin(), frame_ms_.end()));
    return dt_ms;
  }

  Layout layout() const {
    const ImGuiIO& io = ImGui::GetIO();
    Layout at;
    glfwGetFramebufferSize(window_, &at.fb_w, &at.fb_h);
    const float area_w = std::max(1.0f, io.DisplaySize.x - (options_.panel ? kPanelW : 0)), area_h = std::max(1.0f, io.DisplaySize.y);
    const Rgba8& shown = session_.image();
    at.iw = static_cast<float>(shown.width > 0 ? shown.width : image_w_);
    at.ih = static_cast<float>(image_h_);
    at.scale = std::min(area_w / at.iw, area_h / at.ih);
    at.p0 = ImVec2((area_w - at.iw * at.scale) * 0.5f, (area_h - at.ih * at.scale) * 0.5f);
    at.p1 = ImVec2(at.p0.x + at.iw * at.scale, at.p0.y + at.ih * at.scale);
    return at;
  }

  // Mouse → gaze (render pixels of the pane under the cursor), camera navigation, keys.
  void handle_input(const Layout& at, double dt_ms) {
    const ImGuiIO& io = ImGui::GetIO();
    const int rw = session_.settings().render.width;
    if (MouseSource* mouse = session_.mouse()) {
      const float ix = (io.MousePos.x - at.p0.x) / at.scale, iy = (io.MousePos.y - at.p0.y) / at.scale;
      const bool inside =
          !io.WantCaptureMouse && ix >= 0 && iy >= 0 && ix < at.iw && iy < at.ih && glfwGetWindowAttrib(window_, GLFW_HOVERED);
      const float pane_x = std::fmod(ix, static_cast<float>(rw));
      mouse->move(glm::dvec2(pane_x, iy), glfwGetTime(), inside);
    }
    Camera cam = session_.camera();
    if (!io.WantCaptureMouse) {
      if (io.MouseDown[1]) nav_.rotate_view(cam, io.MouseDelta.x, io.MouseDelta.y);
      if (io.MouseDown[2]) nav_.pan(cam, io.MouseDelta.x, io.MouseDelta.y);
      if (io.MouseWheel != 0) nav_.dolly(cam, io.MouseWheel);
    }
    if (!io.WantCaptureKeyboard) handle_keys(cam, dt_ms);
    if (cam.eye != session_.camera().eye || cam.look != session_.camera().look) session_.set_camera(cam);
  }

  void handle_keys(Camera& cam, double dt_ms) {
    const float s = static_cast<float>(std::min(dt_ms, 100.0) / 1000.0);
    glm::vec3 m(0);
    if (ImGui::IsKeyDown(GLFW_KEY_W)) m.z += 1;
    if (ImGui::IsKeyDown(GLFW_KEY_S)) m.z -= 1;
    if (ImGui::IsKeyDown(GLFW_KEY_D)) m.x += 1;
    if (ImGui::IsKeyDown(GLFW_KEY_A)) m.x -= 1;
    if (ImGui::IsKeyDown(GLFW_KEY_E)) m.y += 1;
    if (ImGui::IsKeyDown(GLFW_KEY_Q)) m.y -= 1;
    if (m != glm::vec3(0)) nav_.move(cam, m, s);
    if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) nav_.fly = !nav_.fly;
    if (ImGui::IsKeyPressed(GLFW_KEY_R, false)) cam = home_;
    if (ImGui::IsKeyPressed(GLFW_KEY_TAB, false)) options_.panel = !options_.panel;
    if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) glfwSetWindowShouldClose(window_, 1);
    if (ImGui::IsKeyPressed(GLFW_KEY_P, false) || ImGui::IsKeyPressed(GLFW_KEY_F12, false)) screenshot(numbered_screenshot_path());
    for (int k = 0; k < 4; ++k)
      if (ImGui::IsKeyPressed(GLFW_KEY_1 + k, false)) edit_.mode = static_cast<ViewMode>(k);
  }

  // The panel: every model parameter, applied live.
  void draw_panel() {
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - kPanelW, 0));
    ImGui::SetNextWindowSize(ImVec2(static_cast<float>(kPanelW), io.DisplaySize.y));
    ImGui::Begin("foveal", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
    panel_status();
    panel_mode_and_overlays();
    panel_model();
    panel_eye_and_camera();
    if (ImGui::Button("screenshot (P)")) screenshot(numbered_screenshot_path());
    if (!last_shot_.empty()) ImGui::TextWrapped("wrote %s", last_shot_.c_str());
    if (!panel_error_.empty()) ImGui::TextColored(ImVec4(1, 0.35f, 0.3f, 1), "%s", panel_error_.c_str());
    ImGui::End();
  }

  void panel_status() const {
    const ViewStatus st = session_.status();
    ImGui::Text("frame %.1f ms (%.0f fps)", median_frame_ms_, median_frame_ms_ > 0 ? 1000 / median_frame_ms_ : 0.0);
    ImGui::Text("%s%s", st.stage.c_str(), st.converged ? " (done)" : " ...");
    if (!st.converged) ImGui::ProgressBar(static_cast<float>(st.progress), ImVec2(-1, 0));
    ImGui::Text("render %.0f ms, %.2f M AO rays, %.1f Mrays/s", st.render_ms, st.ao_rays / 1e6, st.rays_per_s / 1e6);
    if (st.fixation)
      ImGui::Text("fixation %.0f, %.0f px   %s", st.fixation->x, st.fixation->y, st.source.c_str());
    else
      ImGui::Text("no fixation yet   %s", st.source.c_str());
    if (st.step)
      ImGui::Text("step %d: sharp %.1f %%, focus %.2f m%s", st.step->step, st.step->sharp_fraction * 100, st.step->focus_depth_m,
                  st.step->blink ? ", blink" : "");
    ImGui::Separator();
  }

  void panel_mode_and_overlays() {
    const char* modes[] = {"foveated", "reference", "side by side", "vision"};
    int mode = static_cast<int>(edit_.mode);
    if (ImGui::Combo("mode", &mode, modes, 4)) edit_.mode = static_cast<ViewMode>(mode);
    ImGui::Checkbox("gaze", &overlays_.gaze);
    ImGui::SameLine();
    ImGui::Checkbox("ROI contours", &overlays_.contours);
    ImGui::SameLine();
    ImGui::Checkbox("budget", &overlays_.budget);
    ImGui::Checkbox("scan path", &overlays_.scanpath);
    ImGui::SameLine();
    ImGui::Checkbox("sharp region", &overlays_.sharp);
  }

  void panel_model() {
    if (ImGui::CollapsingHeader("foveation", ImGuiTreeNodeFlags_DefaultOpen)) {
      FoveationParams& f = edit_.render.foveation;
      ImGui::InputInt("n_max", &f.max_rays, 1, 50);
      ImGui::InputInt("n_min", &f.min_rays, 1, 4);
      ImGui::InputDouble("gamma", &f.gamma, 0.1, 0.5, "%.2f");
      ImGui::InputDouble("beta", &f.beta, 0.1, 0.5, "%.2f");
      ImGui::InputDouble("ellipse a", &f.ellipse_ratio, 0.05, 0.2, "%.3f");
      int seed = static_cast<int>(edit_.render.seed);
      if (ImGui::InputInt("seed", &seed)) edit_.render.seed = static_cast<uint64_t>(std::max(0, seed));
      ImGui::Checkbox("progressive (quarter-resolution preview)", &edit_.progressive);
      ImGui::InputFloat("diff gain", &edit_.diff_gain, 1, 4, "%.0f");
    }
    if (ImGui::CollapsingHeader("display", ImGuiTreeNodeFlags_DefaultOpen)) {
      Display& d = edit_.render.display;
      ImGui::InputDouble("width cm", &d.width_cm, 1, 5, "%.1f");
      ImGui::InputDouble("height cm", &d.height_cm, 1, 5, "%.1f");
      ImGui::InputDouble("distance cm", &d.distance_cm, 1, 10, "%.1f");
      ImGui::InputInt("res x", &d.res_x, 10, 100);
      ImGui::InputInt("res y", &d.res_y, 10, 100);
    }
  }

  void panel_eye_and_camera() {
    if (ImGui::CollapsingHeader("eye (vision mode)", ImGuiTreeNodeFlags_DefaultOpen)) {
      int preset = -1;
      if (ImGui::Combo("preset", &preset, kEyePresets, IM_ARRAYSIZE(kEyePresets)) && preset >= 0)
        std::snprintf(eye_text_, sizeof eye_text_, "%s", kEyePresets[preset]);
      ImGui::InputText("eye", eye_text_, sizeof eye_text_);
      edit_.eye = eye_text_;
      // The pupil shown is the eye's until the user sets one, which then overrides the eye's
      double pupil = edit_.eye_overrides.pupil_diameter_mm.value_or(session_.settings().vision.eye.pupil_diameter_mm);
      if (ImGui::InputDouble("pupil mm", &pupil, 0.5, 1, "%.1f")) edit_.eye_overrides.pupil_diameter_mm = pupil;
      ImGui::InputDouble("starvation", &edit_.vision.starvation, 0.005, 0.05, "%.3f");
      ImGui::InputInt("blink every", &edit_.vision.blink_every, 1, 5);
    }
    if (ImGui::CollapsingHeader("camera", ImGuiTreeNodeFlags_DefaultOpen)) {
      int fly = nav_.fly ? 1 : 0;
      ImGui::RadioButton("orbit", &fly, 0);
      ImGui::SameLine();
      ImGui::RadioButton("fly", &fly, 1);
      nav_.fly = fly == 1;
      ImGui::SameLine();
      if (ImGui::Button("home")) session_.set_camera(home_);
      ImGui::TextWrapped("right-drag: %s, middle-drag: pan, wheel: %s, WASD/QE: fly, F: orbit/fly, R: home", nav_.fly ? "look" : "orbit",
                         nav_.fly ? "forward" : "dolly");
    }
  }

  // Edited parameters go to the session; a refused one stays in the panel with the reason.
  void apply_settings() {
    try {
      session_.set_settings(edit_);
      panel_error_.clear();
    } catch (const Error& e) {
      panel_error_ = e.what();
    }
  }

  // The session (the gaze polled, the renderer's newest stage, the overlays) into the texture, and the frame drawn.
  void draw_image(const Layout& at) {
    session_.update(overlays_);
    const Rgba8& image = session_.image();
    glBindTexture(GL_TEXTURE_2D, texture_);
    if (image.width != tex_w_ || image.height != tex_h_) {
      tex_w_ = image.width;
      tex_h_ = image.height;
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, tex_w_, tex_h_, 0, GL_RGBA, GL_UNSIGNED_BYTE, image.px.data());
    } else {
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, tex_w_, tex_h_, GL_RGBA, GL_UNSIGNED_BYTE, image.px.data());
    }
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(texture_)), at.p0, at.p1);
    ImGui::Render();
    glViewport(0, 0, at.fb_w, at.fb_h);
    glClearColor(0.08f, 0.08f, 0.09f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }

  // A script's last frame: the whole window as drawn (panel included, read back before the swap) and the screenshot.
  void write_finished(const Layout& at) {
    if (!options_.window_screenshot.empty()) {
      Rgba8 shot(at.fb_w, at.fb_h);
      glReadBuffer(GL_BACK);
      glReadPixels(0, 0, at.fb_w, at.fb_h, GL_RGBA, GL_UNSIGNED_BYTE, shot.px.data());
      for (int y = 0; y < at.fb_h / 2; ++y) std::swap_ranges(shot.at(0, y), shot.at(0, y) + at.fb_w * 4, shot.at(0, at.fb_h - 1 - y));
      save_rgba8(shot, options_.window_screenshot);
    }
    if (!options_.screenshot.empty()) screenshot(options_.screenshot);
  }

  std::string numbered_screenshot_path() const { return free_path(options_.screenshot.empty() ? "foveal-view.png" : options_.screenshot); }

  void screenshot(const std::string& path) {
    // Frame times since the start: median and 95th percentile
    std::vector<double> all = all_ms_;
    std::sort(all.begin(), all.end());
    const double p50 = all.empty() ? 0.0 : all[all.size() / 2],
                 p95 = all.empty() ? 0.0 : all[std::min(all.size() - 1, all.size() * 95 / 100)];
    session_.save_screenshot(path, {{"ui_frame_ms", median_frame_ms_},
                                    {"ui_frame_ms_all", {{"median", p50}, {"p95", p95}, {"frames", all.size()}}},
                                    {"overlays", to_string(overlays_)}});
    last_shot_ = path;
  }

  ViewSession& session_;
  WindowOptions options_;
  Overlays& overlays_;
  const Camera home_;
  Navigator nav_;
  ViewSettings edit_;
  char eye_text_[128] = {};
  GLFWwindow* window_ = nullptr;
  bool glfw_ = false, imgui_ = false;
  GLuint texture_ = 0;
  int tex_w_ = 0, tex_h_ = 0, image_w_ = 0, image_h_ = 0;
  std::string panel_error_, last_shot_;
  std::deque<double> frame_ms_;  // the last 60 (the panel)
  std::vector<double> all_ms_;   // every frame's (the screenshot's stats)
  double median_frame_ms_ = 0;
  Timer frame_clock_;
  int frames_ = 0;
  bool finishing_ = false;
};

}  // namespace

int run_window(ViewSession& session, WindowOptions options) { return ViewerWindow(session, std::move(options)).run(); }

}  // namespace foveal
