// apps/main.cpp — the `foveal` command line: parse, run one subcommand, report errors in one line.
#include "commands.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/memory.h"
#include "foveal/util/text.h"

#include <fmt/core.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  foveal::keep_freed_memory();
  foveal::set_input_guard(true);  // no writer of this run may write over one of its inputs
  CLI::App app{"foveal — gaze-contingent ray tracing: foveated ambient occlusion, eye-tracker gaze, simulated human vision", "foveal"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "foveal 0.1.0");
  std::function<int()> run;
  const auto render = foveal::app::add_render_command(app);
  const auto bench = foveal::app::add_bench_command(app);
  const auto gaze = foveal::app::add_gaze_command(app);
  const auto replay = foveal::app::add_replay_command(app);
  const auto simulate = foveal::app::add_simulate_command(app);
  const auto view = foveal::app::add_view_command(app);
  const auto compare = foveal::app::add_compare_command(app);
  const auto perceive = foveal::app::add_perceive_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One clear line instead of CLI11's usage dump
    fmt::print(stderr, "foveal: error: {} (see 'foveal --help')\n", foveal::text::printable(e.what()));
    return e.get_exit_code() != 0 ? e.get_exit_code() : 2;
  }
  try {
    if (app.got_subcommand("render")) return render();
    if (app.got_subcommand("bench")) return bench();
    if (app.got_subcommand("gaze")) return gaze();
    if (app.got_subcommand("replay")) return replay();
    if (app.got_subcommand("simulate")) return simulate();
    if (app.got_subcommand("view")) return view();
    if (app.got_subcommand("compare")) return compare();
    if (app.got_subcommand("perceive")) return perceive();
    return 2;
  } catch (const foveal::Error& e) {
    fmt::print(stderr, "foveal: error: {}\n",
               foveal::text::printable(foveal::app::cli_words(e.what())));  // the library's parameters as options
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "foveal: error: out of memory\n");
  } catch (const std::exception& e) {
    fmt::print(stderr, "foveal: error: {}\n", foveal::text::printable(e.what()));
  }
  return 1;
}
