// foveal/ui/window.h — the viewer's window: GLFW + Dear ImGui (OpenGL 3) around a ViewSession.
//
// The image fills the window left of a parameter panel. The mouse over the image is the gaze
// (when the session's source is the mouse); right-drag orbits the camera (fly mode: looks
// around), middle-drag pans, the wheel dollies, W/A/S/D/Q/E fly. Keys: F orbit/fly, R camera
// home, P (or F12) screenshot, 1–4 modes, Tab hides the panel, Esc quits.
#pragma once

#include "foveal/ui/overlays.h"
#include "foveal/ui/session.h"

#include <string>

namespace foveal {

struct WindowOptions {
  int frames = 0;                 // > 0: show this many frames, wait for the converged image, screenshot, exit
  std::string screenshot;         // the screenshot's path (key P: numbered beside it when it exists)
  std::string window_screenshot;  // --frames: also the whole window, panel included (PNG)
  Overlays overlays;
  bool panel = true;
  double converge_timeout_s = 600;  // --frames: longest wait for the last stage
  std::string title = "foveal view";
};

// Open the window and run until it is closed (or the frames are done). Throws Error, with the
// reason, when no window can be opened (no display).
int run_window(ViewSession& session, WindowOptions options);

}  // namespace foveal
