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

const char* const kEyePresets[] = {"healthy", "glaucoma:0.5", "glaucoma:0.8", "myopia:-3", "hyperopia:2", "presbyopia:60", "astigmatism:2@45"};

}  // namespace

int run_window(ViewSession& session, WindowOptions options) {
  glfwSetErrorCallback([](int, const char* message) { glfw_error = message ? message : "unknown GLFW error"; });
  if (!glfwInit())
    fail("cannot open a window: {} (`foveal view` needs a display: set DISPLAY, or run it under xvfb-run)", glfw_error);
  struct GlfwGuard {
    ~GlfwGuard() { glfwTerminate(); }
  } glfw_guard;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  const int panel_w = 340;
  const int image_w = session.settings().render.width * session.panes();  // the window fits the first mode
  const int image_h = session.settings().render.height;
  int win_w = image_w + (options.panel ? panel_w : 0), win_h = std::max(image_h, options.panel ? 640 : 0);
  if (const GLFWvidmode* mode = glfwGetVideoMode(glfwGetPrimaryMonitor())) {
    win_w = std::min(win_w, mode->width);
    win_h = std::min(win_h, mode->height - 60);
  }
  GLFWwindow* window = glfwCreateWindow(win_w, win_h, options.title.c_str(), nullptr, nullptr);
  if (!window) fail("cannot open a window: {} (needs OpenGL 3.0; under xvfb-run Mesa's software renderer provides it)", glfw_error);
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini in the user's folder
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 130");
  struct ImGuiGuard {
    GLFWwindow* w;
    ~ImGuiGuard() {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
      glfwDestroyWindow(w);
    }
  } imgui_guard{window};

  GLuint texture = 0;
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  int tex_w = 0, tex_h = 0;

  const Camera home = session.camera();
  Navigator nav;
  nav.speed = std::max(1e-3f, glm::length(home.look - home.eye) * 0.5f);
  Overlays& overlays = options.overlays;
  ViewSettings edit = session.settings();
  char eye_text[128] = {};
  std::snprintf(eye_text, sizeof eye_text, "%s", edit.eye.c_str());
  std::string panel_error, last_shot;
  std::deque<double> frame_ms;  // the last 60 (the panel)
  std::vector<double> all_ms;   // every frame's (the screenshot's stats)
  Timer frame_clock;
  int frames = 0;
  bool finishing = false;

  auto screenshot = [&](const std::string& path, double median_frame_ms) {
    // Frame times since the start: median and 95th percentile
    std::vector<double> all = all_ms;
    std::sort(all.begin(), all.end());
    const double p50 = all.empty() ? 0.0 : all[all.size() / 2], p95 = all.empty() ? 0.0 : all[std::min(all.size() - 1, all.size() * 95 / 100)];
    session.save_screenshot(path, {{"ui_frame_ms", median_frame_ms}, {"ui_frame_ms_all", {{"median", p50}, {"p95", p95}, {"frames", all.size()}}},
                                   {"overlays", to_string(overlays)}});
    last_shot = path;
  };

  while (!glfwWindowShouldClose(window)) {
    glfwPollEvents();
    const double dt_ms = frame_clock.ms();
    frame_clock.reset();
    if (frames > 0) {
      frame_ms.push_back(dt_ms);
      all_ms.push_back(dt_ms);
      if (frame_ms.size() > 60) frame_ms.pop_front();
    }
    const double median_frame_ms = frame_ms.empty() ? 0.0 : median(std::vector<double>(frame_ms.begin(), frame_ms.end()));

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();

    // Where the image sits: letterboxed in the area left of the panel
    int fb_w = 0, fb_h = 0;
    glfwGetFramebufferSize(window, &fb_w, &fb_h);
    const float area_w = std::max(1.0f, io.DisplaySize.x - (options.panel ? panel_w : 0)), area_h = std::max(1.0f, io.DisplaySize.y);
    const Rgba8& shown = session.image();
    const float iw = static_cast<float>(shown.width > 0 ? shown.width : image_w), ih = static_cast<float>(image_h);
    const float scale = std::min(area_w / iw, area_h / ih);
    const ImVec2 p0((area_w - iw * scale) * 0.5f, (area_h - ih * scale) * 0.5f), p1(p0.x + iw * scale, p0.y + ih * scale);

    // Mouse → gaze (render pixels of the pane under the cursor) and camera navigation
    const int rw = session.settings().render.width;
    if (MouseSource* mouse = session.mouse()) {
      const float ix = (io.MousePos.x - p0.x) / scale, iy = (io.MousePos.y - p0.y) / scale;
      const bool inside = !io.WantCaptureMouse && ix >= 0 && iy >= 0 && ix < iw && iy < ih && glfwGetWindowAttrib(window, GLFW_HOVERED);
      const float pane_x = std::fmod(ix, static_cast<float>(rw));
      mouse->move(glm::dvec2(pane_x, iy), glfwGetTime(), inside);
    }
    Camera cam = session.camera();
    if (!io.WantCaptureMouse) {
      if (io.MouseDown[1]) nav.rotate_view(cam, io.MouseDelta.x, io.MouseDelta.y);
      if (io.MouseDown[2]) nav.pan(cam, io.MouseDelta.x, io.MouseDelta.y);
      if (io.MouseWheel != 0) nav.dolly(cam, io.MouseWheel);
    }
    if (!io.WantCaptureKeyboard) {
      const float s = static_cast<float>(std::min(dt_ms, 100.0) / 1000.0);
      glm::vec3 m(0);
      if (ImGui::IsKeyDown(GLFW_KEY_W)) m.z += 1;
      if (ImGui::IsKeyDown(GLFW_KEY_S)) m.z -= 1;
      if (ImGui::IsKeyDown(GLFW_KEY_D)) m.x += 1;
      if (ImGui::IsKeyDown(GLFW_KEY_A)) m.x -= 1;
      if (ImGui::IsKeyDown(GLFW_KEY_E)) m.y += 1;
      if (ImGui::IsKeyDown(GLFW_KEY_Q)) m.y -= 1;
      if (m != glm::vec3(0)) nav.move(cam, m, s);
      if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) nav.fly = !nav.fly;
      if (ImGui::IsKeyPressed(GLFW_KEY_R, false)) cam = home;
      if (ImGui::IsKeyPressed(GLFW_KEY_TAB, false)) options.panel = !options.panel;
      if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) glfwSetWindowShouldClose(window, 1);
      if (ImGui::IsKeyPressed(GLFW_KEY_P, false) || ImGui::IsKeyPressed(GLFW_KEY_F12, false))
        screenshot(free_path(options.screenshot.empty() ? "foveal-view.png" : options.screenshot), median_frame_ms);
      for (int k = 0; k < 4; ++k)
        if (ImGui::IsKeyPressed(GLFW_KEY_1 + k, false)) edit.mode = static_cast<ViewMode>(k);
    }
    if (cam.eye != session.camera().eye || cam.look != session.camera().look) session.set_camera(cam);

    // The panel: every model parameter, applied live
    if (options.panel) {
      ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - panel_w, 0));
      ImGui::SetNextWindowSize(ImVec2(static_cast<float>(panel_w), io.DisplaySize.y));
      ImGui::Begin("foveal", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
      const ViewStatus st = session.status();
      ImGui::Text("frame %.1f ms (%.0f fps)", median_frame_ms, median_frame_ms > 0 ? 1000 / median_frame_ms : 0.0);
      ImGui::Text("%s%s", st.stage.c_str(), st.converged ? " (done)" : " ...");
      if (!st.converged) ImGui::ProgressBar(static_cast<float>(st.progress), ImVec2(-1, 0));
      ImGui::Text("render %.0f ms, %.2f M AO rays, %.1f Mrays/s", st.render_ms, st.ao_rays / 1e6, st.rays_per_s / 1e6);
      if (st.fixation) ImGui::Text("fixation %.0f, %.0f px   %s", st.fixation->x, st.fixation->y, st.source.c_str());
      else ImGui::Text("no fixation yet   %s", st.source.c_str());
      if (st.step) ImGui::Text("step %d: sharp %.1f %%, focus %.2f m%s", st.step->step, st.step->sharp_fraction * 100, st.step->focus_depth_m,
                               st.step->blink ? ", blink" : "");
      ImGui::Separator();
      const char* modes[] = {"foveated", "reference", "side by side", "vision"};
      int mode = static_cast<int>(edit.mode);
      if (ImGui::Combo("mode", &mode, modes, 4)) edit.mode = static_cast<ViewMode>(mode);
      ImGui::Checkbox("gaze", &overlays.gaze);
      ImGui::SameLine();
      ImGui::Checkbox("ROI contours", &overlays.contours);
      ImGui::SameLine();
      ImGui::Checkbox("budget", &overlays.budget);
      ImGui::Checkbox("scan path", &overlays.scanpath);
      ImGui::SameLine();
      ImGui::Checkbox("sharp region", &overlays.sharp);
      if (ImGui::CollapsingHeader("foveation", ImGuiTreeNodeFlags_DefaultOpen)) {
        FoveationParams& f = edit.render.foveation;
        ImGui::InputInt("n_max", &f.max_rays, 1, 50);
        ImGui::InputInt("n_min", &f.min_rays, 1, 4);
        ImGui::InputDouble("gamma", &f.gamma, 0.1, 0.5, "%.2f");
        ImGui::InputDouble("beta", &f.beta, 0.1, 0.5, "%.2f");
        ImGui::InputDouble("ellipse a", &f.ellipse_ratio, 0.05, 0.2, "%.3f");
        int seed = static_cast<int>(edit.render.seed);
        if (ImGui::InputInt("seed", &seed)) edit.render.seed = static_cast<uint64_t>(std::max(0, seed));
        ImGui::Checkbox("progressive (quarter-resolution preview)", &edit.progressive);
        ImGui::InputFloat("diff gain", &edit.diff_gain, 1, 4, "%.0f");
      }
      if (ImGui::CollapsingHeader("display", ImGuiTreeNodeFlags_DefaultOpen)) {
        Display& d = edit.render.display;
        ImGui::InputDouble("width cm", &d.width_cm, 1, 5, "%.1f");
        ImGui::InputDouble("height cm", &d.height_cm, 1, 5, "%.1f");
        ImGui::InputDouble("distance cm", &d.distance_cm, 1, 10, "%.1f");
        ImGui::InputInt("res x", &d.res_x, 10, 100);
        ImGui::InputInt("res y", &d.res_y, 10, 100);
      }
      if (ImGui::CollapsingHeader("eye (vision mode)", ImGuiTreeNodeFlags_DefaultOpen)) {
        int preset = -1;
        if (ImGui::Combo("preset", &preset, kEyePresets, IM_ARRAYSIZE(kEyePresets)) && preset >= 0)
          std::snprintf(eye_text, sizeof eye_text, "%s", kEyePresets[preset]);
        ImGui::InputText("eye", eye_text, sizeof eye_text);
        edit.eye = eye_text;
        // The pupil shown is the eye's until the user sets one, which then overrides the eye's
        double pupil = edit.eye_overrides.pupil_diameter_mm.value_or(session.settings().vision.eye.pupil_diameter_mm);
        if (ImGui::InputDouble("pupil mm", &pupil, 0.5, 1, "%.1f")) edit.eye_overrides.pupil_diameter_mm = pupil;
        ImGui::InputDouble("starvation", &edit.vision.starvation, 0.005, 0.05, "%.3f");
        ImGui::InputInt("blink every", &edit.vision.blink_every, 1, 5);
      }
      if (ImGui::CollapsingHeader("camera", ImGuiTreeNodeFlags_DefaultOpen)) {
        int fly = nav.fly ? 1 : 0;
        ImGui::RadioButton("orbit", &fly, 0);
        ImGui::SameLine();
        ImGui::RadioButton("fly", &fly, 1);
        nav.fly = fly == 1;
        ImGui::SameLine();
        if (ImGui::Button("home")) session.set_camera(home);
        ImGui::TextWrapped("right-drag: %s, middle-drag: pan, wheel: %s, WASD/QE: fly, F: orbit/fly, R: home",
                           nav.fly ? "look" : "orbit", nav.fly ? "forward" : "dolly");
      }
      if (ImGui::Button("screenshot (P)"))
        screenshot(free_path(options.screenshot.empty() ? "foveal-view.png" : options.screenshot), median_frame_ms);
      if (!last_shot.empty()) ImGui::TextWrapped("wrote %s", last_shot.c_str());
      if (!panel_error.empty()) ImGui::TextColored(ImVec4(1, 0.35f, 0.3f, 1), "%s", panel_error.c_str());
      ImGui::End();
    }
    // Apply edited parameters (a refused one stays in the panel with the reason)
    try {
      session.set_settings(edit);
      panel_error.clear();
    } catch (const Error& e) {
      panel_error = e.what();
    }

    // The session: poll the gaze, collect the renderer's newest stage, draw the overlays
    session.update(overlays);
    const Rgba8& image = session.image();
    glBindTexture(GL_TEXTURE_2D, texture);
    if (image.width != tex_w || image.height != tex_h) {
      tex_w = image.width;
      tex_h = image.height;
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, tex_w, tex_h, 0, GL_RGBA, GL_UNSIGNED_BYTE, image.px.data());
    } else {
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, tex_w, tex_h, GL_RGBA, GL_UNSIGNED_BYTE, image.px.data());
    }
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(texture)), p0, p1);

    ImGui::Render();
    glViewport(0, 0, fb_w, fb_h);
    glClearColor(0.08f, 0.08f, 0.09f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    if (finishing) {
      if (!options.window_screenshot.empty()) {
        // The whole window as drawn this frame (panel included), read back before the swap
        Rgba8 shot(fb_w, fb_h);
        glReadBuffer(GL_BACK);
        glReadPixels(0, 0, fb_w, fb_h, GL_RGBA, GL_UNSIGNED_BYTE, shot.px.data());
        for (int y = 0; y < fb_h / 2; ++y) std::swap_ranges(shot.at(0, y), shot.at(0, y) + fb_w * 4, shot.at(0, fb_h - 1 - y));
        save_rgba8(shot, options.window_screenshot);
      }
      if (!options.screenshot.empty()) screenshot(options.screenshot, median_frame_ms);
      break;
    }
    glfwSwapBuffers(window);
    ++frames;
    if (options.frames > 0 && frames >= options.frames) {
      // Scripts: wait for the current inputs' last stage, show it once more, then write it
      if (!session.wait_until_converged(options.converge_timeout_s, overlays))
        fail("the render did not finish within {:.0f} s", options.converge_timeout_s);
      if (session.status().stage.starts_with("error")) fail("{}", session.status().stage.substr(7));
      finishing = true;
      frame_clock.reset();  // the wait is not a frame
      continue;
    }
    // About 60 frames a second at most: the renderer gets the rest of the CPU
    const double spent = frame_clock.ms();
    if (spent < 16) std::this_thread::sleep_for(std::chrono::microseconds(static_cast<int>((16 - spent) * 1000)));
  }
  glDeleteTextures(1, &texture);
  return 0;
}

}  // namespace foveal
