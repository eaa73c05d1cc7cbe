// A killed run's staging files are removed by the next run into the same target; a live one's kept.
#include "foveal/util/files.h"
#include "foveal/util/gzip.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

pid_t a_process_that_has_ended() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;
}

}  // namespace

TEST(Files, AKilledRunsPartialsAreRemovedByTheNextRunAndALiveOnesKept) {
  const fs::path dir = fs::temp_directory_path() / ("foveal-files-test-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path dead = dir / (".out.partial-" + std::to_string(a_process_that_has_ended()) + "-0");
  const fs::path live = dir / (".out.partial-" + std::to_string(getppid()) + "-0");  // the parent runs
  const fs::path other = dir / (".other.partial-" + std::to_string(a_process_that_has_ended()) + "-0");
  for (const fs::path& p : {dead, live, other}) {
    fs::create_directories(p);
    std::ofstream(p / "frame.png") << "x";
  }
  {
    foveal::StagedFolder staged((dir / "out").string());
    std::ofstream(fs::path(staged.path()) / "a.png") << "a";
    staged.commit();
  }
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(other));  // another target's
  EXPECT_TRUE(fs::exists(dir / "out" / "a.png"));
  // A file written atomically clears its own target's leftovers too
  const fs::path dead_file = dir / (".t.tsv.gz.partial-" + std::to_string(a_process_that_has_ended()) + "-3");
  std::ofstream(dead_file) << "partial";
  foveal::write_file_atomically((dir / "t.tsv.gz").string(), "1\t2\n", true);
  EXPECT_FALSE(fs::exists(dead_file));
  EXPECT_EQ(foveal::read_gzip_file((dir / "t.tsv.gz").string()), "1\t2\n");
  fs::remove_all(dir);
}

TEST(Files, AnOutputFileIsCheckedBeforeAnyWork) {
  const fs::path dir = fs::temp_directory_path() / ("foveal-output-test-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const auto message = [](const std::string& path, const std::vector<std::string>& extensions = {}) {
    try {
      foveal::check_output_file(path, extensions);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message((dir / "a.json").string()), "");           // a new file in a folder that exists
  EXPECT_EQ(message("relative.json"), "");                     // in the working folder
  EXPECT_EQ(message((dir / "a.PNG").string(), {".png"}), "");  // the extension in any case
  EXPECT_NE(message((dir / "missing" / "a.json").string()).find("the folder " + (dir / "missing").string() + " does not exist"),
            std::string::npos);
  EXPECT_NE(message(dir.string()).find("is a folder"), std::string::npos);
  std::ofstream(dir / "file") << "x";
  EXPECT_NE(message((dir / "file" / "a.json").string()).find("is not a folder"), std::string::npos);
  EXPECT_NE(message((dir / "a.gif").string(), {".png", ".svg"}).find("must end in .png or .svg"), std::string::npos);
  EXPECT_NE(message("").find("needs a name"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "a.json"));  // nothing created (read-only places: below)
  fs::remove_all(dir);
}

// The outputs of one command line, against each other and its other arguments (main.cpp passes them)
TEST(Files, OutputsAreApartFromEachOtherAndFromTheInputs) {
  const fs::path dir = fs::temp_directory_path() / ("foveal-apart-test-" + std::to_string(getpid()));
  fs::create_directories(dir / "sub");
  std::ofstream(dir / "rec.csv") << "t,x,y\n";
  const auto message = [](const std::vector<foveal::OptionPath>& outputs, const std::vector<foveal::OptionPath>& arguments) {
    try {
      foveal::check_outputs_apart(outputs, arguments);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string rec = (dir / "rec.csv").string(), other_spelling = (dir / "sub" / ".." / "rec.csv").string();
  const std::string a = (dir / "a.json").string(), b = (dir / "b.md").string();
  EXPECT_EQ(message({{"--json", a}, {"--markdown", b}}, {{"--recording", rec}, {"--size", "64x40"}}), "");
  EXPECT_EQ(message({{"--json", rec}}, {{"--recording", (dir / "missing.csv").string()}}), "");  // not an input: overwritten
  EXPECT_EQ(message({{"--json", rec}}, {{"--json", ""}}), "");
  EXPECT_EQ(message({{"--json", other_spelling}}, {{"--recording", rec}}),
            "--json " + other_spelling + ": is --recording " + rec + ", an input of this run; foveal never writes over its inputs");
  const std::string a_again = (dir / "sub" / ".." / "a.json").string();
  EXPECT_EQ(message({{"--json", a}, {"--markdown", a_again}}, {}),
            "--json " + a + " and --markdown " + a_again +
                ": two outputs into one file (the second would replace the first); give each its own name");
  fs::create_hard_link(dir / "rec.csv", dir / "link.csv");  // one file under two names
  EXPECT_NE(message({{"--samples-out", (dir / "link.csv").string()}}, {{"RECORDING", rec}}).find("is RECORDING"), std::string::npos);
  EXPECT_FALSE(fs::exists(a));  // nothing created
  fs::remove_all(dir);
}

// A read-only file or folder is left alone by every user, root too (the system would let root
// replace it): the check before the work, the writers and a folder of outputs all refuse it.
TEST(Files, ReadOnlyFilesAndFoldersAreNeverReplaced) {
  const fs::path dir = fs::temp_directory_path() / ("foveal-read-only-test-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const auto message = [](const auto& write) {
    try {
      write();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const fs::path data = dir / "recording.asc";
  std::ofstream(data) << "the data";
  fs::permissions(data, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  EXPECT_NE(message([&] { foveal::check_output_file(data.string()); }).find("is read-only"), std::string::npos);
  EXPECT_NE(message([&] { foveal::write_file_atomically(data.string(), "{}", false); }).find(data.string() + ": is read-only"),
            std::string::npos);
  std::ifstream in(data);
  std::string kept((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(kept, "the data");
  // A new file in a read-only folder
  const fs::path locked = dir / "locked";
  fs::create_directories(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  EXPECT_NE(message([&] { foveal::check_output_file((locked / "a.json").string()); }).find("is read-only"), std::string::npos);
  EXPECT_NE(message([&] { foveal::write_file_atomically((locked / "a.json").string(), "{}", false); }).find("read-only folder"),
            std::string::npos);
  EXPECT_NE(message([&] { foveal::StagedFolder staged((locked / "frames").string()); }).find("read-only folder"), std::string::npos);
  EXPECT_NE(message([&] { foveal::StagedFolder staged(locked.string()); }).find("read-only folder"), std::string::npos);
  EXPECT_FALSE(fs::exists(locked / "a.json"));
  fs::permissions(locked, fs::perms::owner_all);
  // A folder of outputs whose target holds a read-only file of the same name: nothing is moved
  const fs::path out = dir / "out";
  fs::create_directories(out);
  std::ofstream(out / "b.png") << "kept";
  fs::permissions(out / "b.png", fs::perms::owner_read);
  {
    foveal::StagedFolder staged(out.string());
    std::ofstream(fs::path(staged.path()) / "a.png") << "a";
    std::ofstream(fs::path(staged.path()) / "b.png") << "b";
    EXPECT_NE(message([&] { staged.commit(); }).find("b.png: is read-only"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(out / "a.png"));
  std::ifstream b(out / "b.png");
  std::string b_kept((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
  EXPECT_EQ(b_kept, "kept");
  fs::permissions(out / "b.png", fs::perms::owner_all);
  fs::permissions(data, fs::perms::owner_all);
  fs::remove_all(dir);
}
