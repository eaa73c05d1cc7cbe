// foveal/util/files.h — two rules every writer follows.
//
// Never over an input: an output that is (or will be) the same file as one of the run's inputs is
// refused before anything is written (`perceive x.png -o x.png` overwrote its input: issue 36's
// finding 1). check_output_is_not_input is the explicit check a command makes up front; with the
// input guard on (the command line turns it on), every input read through foveal's readers is
// remembered and every writer refuses to write over one — one rule for every writer. A Python
// session may rewrite its own files, so the guard is off unless turned on.
//
// Never over a read-only file, nor into a read-only folder, whoever runs it: the system lets root
// (a container's user, often) replace them, and a bench's --json once replaced a read-only recording so.
//
// All or nothing: a folder of outputs is written into a staging folder beside it and moved into
// place when the run succeeds, so a failed run leaves no partial output (finding 2).
#pragma once

#include <string>
#include <vector>

namespace foveal {

// Throws Error ("OPTION OUTPUT: is the input INPUT; foveal never writes over its inputs") when
// `output` names the same file or folder as `input` (after resolving links, . and ..).
void check_output_is_not_input(const std::string& output, const std::string& input, const char* option);

// An option's value on a command line: `option` as the user gave it, `path` its text.
struct OptionPath {
  std::string option, path;
};
// The outputs of one command line against each other and against its other arguments, checked when
// it is read: no two outputs may name one file (the later would replace the earlier: `--json r.txt
// --markdown r.txt` kept only the Markdown), and no output may be the same file as another argument
// that names an existing file or folder (an input: a bench's --json named its own recording and was
// refused only once its minutes of work were done). Throws Error naming both options.
void check_outputs_apart(const std::vector<OptionPath>& outputs, const std::vector<OptionPath>& arguments);

// Whether a file can be written at `path`, checked before a run does the work: throws Error naming
// the path and the reason (its folder is missing or is no folder, the path is a folder, nothing
// may be written there, or its extension is none of `extensions`, where given: lower case, with
// the dot). A bench's --json named a missing folder and failed only once its minutes of work were
// done. A read-only file or folder is refused, as by the writers. Creates nothing.
void check_output_file(const std::string& path, const std::vector<std::string>& extensions = {});

// The file name's extension in lower case, with its dot (".PLY" → ".ply"; "" for none): what
// every reader that picks a format by the name compares.
std::string lower_extension(const std::string& path);

void set_input_guard(bool on);
void note_input(const std::string& path);  // a reader's input (no effect with the guard off)
// A writer's target: throws Error naming it where it is an input or read-only (or in a read-only folder)
void check_not_an_input(const std::string& output);

// Remove what a killed run left beside `target` (".NAME.partial-PID-N" of a process that no longer
// runs).
void remove_stale_partials(const std::string& target);
// A fresh path beside `target` for its partial copy, ".NAME.partial-PID-N" (after removing a killed
// run's): what StagedFolder and write_file_atomically (util/gzip.h) stage into.
std::string partial_path(const std::string& target);

// A staging folder for a folder of outputs: files go into path(), commit() moves them into the
// target folder (created if missing; files of the same name replaced), and a StagedFolder that was
// never committed removes itself with everything in it.
class StagedFolder {
 public:
  explicit StagedFolder(std::string target);
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;
  const std::string& path() const { return staging_; }
  const std::string& target() const { return target_; }
  void commit();

 private:
  std::string target_, staging_;
  bool committed_ = false;
};

}  // namespace foveal
