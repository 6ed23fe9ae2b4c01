// RunFolder: the marker lists what a run wrote, replacing removes only that, the user's files and
// folders (and an input) are never touched, and the lock keeps a second writer out.
#include "acquisition/run_folder.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

void Touch(const std::string& path, const std::string& text = "x") {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << text;
}

RunFolder::Options With(RunFolder::Earlier earlier, std::vector<std::string> inputs = {}) {
  RunFolder::Options o;
  o.earlier = earlier;
  o.inputs = std::move(inputs);
  return o;
}

// The message of the InputError that opening `dir` throws ("" when none).
std::string Refusal(const std::string& dir, const RunFolder::Options& options) {
  try {
    RunFolder folder(dir, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(RunFolder, TheMarkerListsWhatTheRunWroteInOrder) {
  testing::TempDir dir;
  const std::string out = dir / "run";
  {
    RunFolder run(out, With(RunFolder::kRefuse));
    EXPECT_EQ(run.File("report.json"), out + "/report.json");
    Touch(run.File("keyframes/1.png"));
    Touch(run.File("keyframes/1.png"));  // written again: listed once
    EXPECT_EQ(run.Folder("undistorted/color"), out + "/undistorted/color");
  }
  EXPECT_TRUE(RunFolder::IsMarked(out));
  EXPECT_EQ(
      RunFolder::ReadMarker(out),
      (std::vector<std::string>{"file report.json", "folder keyframes", "file keyframes/1.png",
                                "folder undistorted", "folder undistorted/color"}));
  EXPECT_EQ(ReadTextFile(out + "/.glassfusion-run").rfind("glassfusion-run 1\n", 0), 0u);
}

TEST(RunFolder, ReplaceRemovesOnlyListedFilesAndTheFoldersLeftEmpty) {
  testing::TempDir dir;
  const std::string out = dir / "run";
  {
    RunFolder run(out, With(RunFolder::kRefuse));
    for (const char* f : {"a.txt", "keyframes/1.png", "undistorted/color/1.png", "deep/er/x"})
      Touch(run.File(f));
  }
  Touch(out + "/notes.txt", "mine");
  Touch(out + "/undistorted/mine.txt", "mine");
  EXPECT_TRUE(Has(Refusal(out, With(RunFolder::kRefuse)), "--force"));
  {
    RunFolder run(out, With(RunFolder::kReplace));
    EXPECT_FALSE(fs::exists(out + "/a.txt"));
    EXPECT_FALSE(fs::exists(out + "/keyframes"));
    EXPECT_FALSE(fs::exists(out + "/deep"));
    EXPECT_FALSE(fs::exists(out + "/undistorted/color"));
    EXPECT_EQ(ReadTextFile(out + "/notes.txt"), "mine");
    EXPECT_EQ(ReadTextFile(out + "/undistorted/mine.txt"), "mine");
  }
  // undistorted/ could not be removed (the user's file is in it): it stays listed.
  EXPECT_EQ(RunFolder::ReadMarker(out), std::vector<std::string>{"folder undistorted"});
}

TEST(RunFolder, AFolderWithoutMarkerIsNeverTouched) {
  testing::TempDir dir;
  const std::string cap = dir / "cap";
  Touch(cap + "/camera.json");
  Touch(cap + "/thesis.tex");
  for (auto earlier : {RunFolder::kRefuse, RunFolder::kReplace, RunFolder::kKeep})
    EXPECT_TRUE(Has(Refusal(cap, With(earlier)), "holds no run")) << earlier;
  EXPECT_EQ(std::distance(fs::directory_iterator(cap), fs::directory_iterator()), 2);
}

TEST(RunFolder, RefusesToBeContainOrLieInsideAnInput) {
  testing::TempDir dir;
  const std::string cap = dir / "x/cap";
  Touch(cap + "/depth.txt");
  Touch(dir / "x/rec.oni");
  const auto is = Refusal(cap + "/", With(RunFolder::kReplace, {cap}));
  EXPECT_TRUE(Has(is, "is the input")) << is;
  EXPECT_TRUE(Has(Refusal(dir / "x", With(RunFolder::kReplace, {cap})), "contains the input"));
  EXPECT_TRUE(Has(Refusal(dir / "x/./cap/run", With(RunFolder::kReplace, {dir / "x/cap"})),
                  "lies inside the input"));
  EXPECT_TRUE(Has(Refusal(dir / "x", With(RunFolder::kReplace, {dir / "x/rec.oni"})),
                  "contains the input"));
  EXPECT_FALSE(fs::exists(cap + "/run"));
  EXPECT_FALSE(fs::exists(cap + "/.glassfusion-run.lock"));
  // Beside the input, or an input that is no path (a device): fine.
  EXPECT_EQ(Refusal(dir / "x/run", With(RunFolder::kRefuse, {cap, "dummy"})), "");
}

TEST(RunFolder, NeverOverwritesAFileItDidNotWrite) {
  testing::TempDir dir;
  const std::string out = dir / "run";
  { RunFolder run(out, With(RunFolder::kRefuse)); }
  Touch(out + "/map.ply", "the user's");
  RunFolder run(out, With(RunFolder::kKeep));
  EXPECT_THROW(run.File("map.ply"), InputError);
  EXPECT_THROW(run.File("../escape.txt"), InputError);
  EXPECT_THROW(run.File(".glassfusion-run"), InputError);
  EXPECT_EQ(ReadTextFile(out + "/map.ply"), "the user's");
}

TEST(RunFolder, AListedPathThroughALinkOutsideIsNotRemoved) {
  testing::TempDir dir;
  const std::string out = dir / "run";
  { Touch(RunFolder(out, With(RunFolder::kRefuse)).File("keyframes/1.png")); }
  // The user replaces keyframes/ by a link to their own folder holding a file of that name.
  Touch(dir / "elsewhere/1.png", "precious");
  fs::remove_all(out + "/keyframes");
  fs::create_directory_symlink(dir / "elsewhere", out + "/keyframes");
  { RunFolder run(out, With(RunFolder::kReplace)); }
  EXPECT_EQ(ReadTextFile(dir / "elsewhere/1.png"), "precious");
}

TEST(RunFolder, ATornOrForeignMarkerNamesNothing) {
  testing::TempDir dir;
  const std::string out = dir / "run";
  Touch(out + "/.glassfusion-run", "glassfusion-run 1\nfile a.txt\nfile ../up.txt\nfile b.t");
  Touch(out + "/a.txt");
  Touch(out + "/b.txt", "mine");
  Touch(dir / "up.txt", "mine");
  { RunFolder run(out, With(RunFolder::kReplace)); }
  EXPECT_FALSE(fs::exists(out + "/a.txt"));
  EXPECT_TRUE(fs::exists(out + "/b.txt"));
  EXPECT_TRUE(fs::exists(dir / "up.txt"));
  Touch(dir / "other/.glassfusion-run", "my own notes\nfile b.txt\n");
  Touch(dir / "other/b.txt");
  EXPECT_TRUE(Has(Refusal(dir / "other", With(RunFolder::kReplace)), "not a GlassFusion marker"));
  EXPECT_TRUE(fs::exists(dir / "other/b.txt"));
}

TEST(RunFolder, ASecondWriterIsRefusedWhileTheFirstHoldsTheLock) {
  testing::TempDir dir;
  const std::string out = dir / "run";
  auto first = std::make_unique<RunFolder>(out, With(RunFolder::kRefuse));
  Touch(first->File("report.json"));
  for (auto earlier : {RunFolder::kRefuse, RunFolder::kReplace, RunFolder::kKeep}) {
    const std::string why = Refusal(out, With(earlier));
    EXPECT_TRUE(Has(
        why, "another glassfusion run is writing here (pid " + std::to_string(::getpid()) + ")"))
        << why;
  }
  // From another process too (flock is per open file, so this is the same check).
  const pid_t child = ::fork();
  if (child == 0) _exit(Has(Refusal(out, With(RunFolder::kReplace)), "another") ? 0 : 1);
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_TRUE(fs::exists(out + "/report.json"));
  first.reset();  // the lock goes with it
  EXPECT_EQ(Refusal(out, With(RunFolder::kReplace)), "");
}

TEST(RunFolder, SharedWritersAddToOneMarker) {
  testing::TempDir dir;
  const std::string out = dir / "batch";
  RunFolder::Options shared = With(RunFolder::kKeep);
  shared.shared = true;
  {
    RunFolder a(out, shared), b(out, shared);
    Touch(a.File("batch/0.json"));
    Touch(b.File("batch/1.json"));
    EXPECT_TRUE(Has(Refusal(out, With(RunFolder::kKeep)), "another glassfusion run"));
  }
  RunFolder again(out, With(RunFolder::kKeep));
  EXPECT_EQ(RunFolder::ReadMarker(out),
            (std::vector<std::string>{"folder batch", "file batch/0.json", "file batch/1.json"}));
}

TEST(RunFolder, RecordTreeListsAFolderMovedIntoPlace) {
  testing::TempDir dir;
  const std::string out = dir / "demo";
  {
    RunFolder run(out, With(RunFolder::kRefuse));
    Touch(out + "/scene/depth/1.png");
    Touch(out + "/scene/depth.txt");
    run.RecordTree("scene");
  }
  Touch(out + "/mine.txt");
  { RunFolder run(out, With(RunFolder::kReplace)); }
  EXPECT_FALSE(fs::exists(out + "/scene"));
  EXPECT_TRUE(fs::exists(out + "/mine.txt"));
}

}  // namespace
}  // namespace gf
