// apps/main.cpp — the `foveal` command line: parse, run one subcommand, report errors in one line.
#include "commands.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/memory.h"
#include "foveal/util/text.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

namespace {

// Every number an option takes is finite, and an unsigned one not negative. CLI11's ranges let NaN through (each comparison with it
// is false), and an option the chosen mode leaves unused (perceive's fixation filter without
// --gaze) was never checked at all: `--ivt-threshold nan` ran as if it had not been given.
// (--ao-distance's documented inf is text, parsed by its command.)
void refuse_non_finite(const CLI::App& app) {
  for (const CLI::Option* option : app.get_options()) {
    const std::string type = option->get_type_name();
    if (type.rfind("UINT", 0) == 0)  // (CLI11 reads "-1" as 2^64 − 1)
      for (const std::string& value : option->results())
        if (value.find('-') != std::string::npos) foveal::fail("{}: must be 0 or more, got {}", option->get_name(), value);
    if (type.rfind("FLOAT", 0) != 0) continue;
    for (const std::string& value : option->results()) {
      char* end = nullptr;
      const double x = std::strtod(value.c_str(), &end);
      if (end != value.c_str() && !std::isfinite(x)) foveal::fail("{}: must be a finite number, got {}", option->get_name(), value);
    }
  }
  for (const CLI::App* sub : app.get_subcommands()) refuse_non_finite(*sub);
}

// Each parsed (sub)command's outputs — the options output_file() checks — and its other arguments,
// from the command down through the subcommand chosen
void collect_paths(CLI::App& app, std::vector<foveal::OptionPath>& outputs, std::vector<foveal::OptionPath>& arguments) {
  for (CLI::Option* option : app.get_options()) {
    if (option->count() == 0) continue;
    bool output = false;
    try {
      option->get_validator(foveal::app::kOutputFileValidator);
      output = true;
    } catch (const CLI::OptionNotFound&) {}
    const std::string name = option->get_name();
    for (const std::string& value : option->results()) (output ? outputs : arguments).push_back({name, value});
  }
  for (CLI::App* sub : app.get_subcommands()) collect_paths(*sub, outputs, arguments);
}

// No two outputs into one file, and none over an input: checked before the run, not when it writes
void refuse_outputs_over_arguments(CLI::App& app) {
  std::vector<foveal::OptionPath> outputs, arguments;
  collect_paths(app, outputs, arguments);
  foveal::check_outputs_apart(outputs, arguments);
}

}  // namespace

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
    // One clear line instead of CLI11's usage dump, pointing to the help of the command it is about
    std::string command = "foveal";
    const CLI::App* deepest = &app;
    while (!deepest->get_subcommands().empty()) {
      deepest = deepest->get_subcommands().front();
      command += " " + deepest->get_name();
    }
    std::string what = e.what();
    // A command that is none of those there are: name it and them ("A subcommand is required" named neither)
    const std::vector<const CLI::App*> known = deepest->get_subcommands([](const CLI::App*) { return true; });
    if (!known.empty() && what.find("subcommand") != std::string::npos) {
      const int depth = static_cast<int>(std::count(command.begin(), command.end(), ' '));
      std::vector<std::string> names;
      for (const CLI::App* k : known) names.push_back(k->get_name());
      const std::string given = argc > depth + 1 ? argv[depth + 1] : "";
      what = given.empty() || given[0] == '-'
                 ? fmt::format("a command is needed: {}", fmt::join(names, ", "))
                 : fmt::format("'{}' is no command of {} (the commands: {})", given, command, fmt::join(names, ", "));
    }
    fmt::print(stderr, "foveal: error: {} (see '{} --help')\n", foveal::text::printable(what), command);
    return e.get_exit_code() != 0 ? e.get_exit_code() : 2;
  }
  try {
    refuse_non_finite(app);
    refuse_outputs_over_arguments(app);
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
