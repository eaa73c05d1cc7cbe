// apps/commands.h — the subcommands of the `foveal` executable.
#pragma once

#include "foveal/perception/foveation.h"
#include "foveal/scene/scene.h"

#include <CLI/CLI.hpp>

#include <functional>

namespace foveal::app {

// Each adds its subcommand to the app and returns the function that runs it after parsing.
std::function<int()> add_render_command(CLI::App& app);
std::function<int()> add_bench_command(CLI::App& app);

// Options shared by the commands that render: parsed text, turned into params by each command.
struct ViewOptions {
  std::string scene = "builtin:box";
  std::string camera;
  std::string eye, look, up = "0,1,0";
  double fov = 0;
  std::string size = "840x525";
  std::string display = "47.5,30,60,1680,1050";
  int threads = 0;
};

// Camera from the options: a named one, explicit eye/look/up/fov, the scene's first, or a default.
Camera resolve_camera(const Scene& scene, const ViewOptions& options);
// Display from "W_CM,H_CM,DIST_CM[,RES_X,RES_Y]"; without a resolution the render size is used.
Display resolve_display(const std::string& text, glm::ivec2 render_size);
// Add the --scene/--camera/--eye/…/--threads options to a subcommand.
void add_view_options(CLI::App& command, ViewOptions& options);

}  // namespace foveal::app
