// apps/commands.h — the subcommands of the `foveal` executable.
#pragma once

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

}  // namespace foveal::app
