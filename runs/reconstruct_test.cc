// `reconstruct` in-process on a short synthetic capture: the run folder holds every output the
// README lists, the mesh (--mesh) and the page that its finishing step writes, and report.json
// says the run is complete with the figures the summary gives.
#include "runs/reconstruct.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "acquisition/file_util.h"
#include "acquisition/run_layout.h"
#include "datasets/synth.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

TEST(Reconstruct, WritesTheRunFolderWithItsMeshAndPage) {
  testing::TempDir tmp;
  synth::SynthOptions scene;
  scene.frames = 12;
  scene.seed = 11;
  synth::GenerateDataset(scene, tmp / "scene");
  ReconstructOptions options;
  options.input = tmp / "scene";
  options.out_dir = tmp / "run";
  options.mesh = true;
  const ReconstructionSummary s = RunReconstruct(options);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.frames, 12);
  const RunLayout run(options.out_dir);
  for (const char* f : {RunLayout::kTrajectory, RunLayout::kCamera, RunLayout::kReport,
                        RunLayout::kPage, RunLayout::kMap, RunLayout::kMesh})
    EXPECT_TRUE(fs::exists(run.Path(f))) << f;
  EXPECT_TRUE(fs::is_directory(run.Path(RunLayout::kKeyframes)));
  const nlohmann::json report = nlohmann::json::parse(ReadTextFile(run.Path(RunLayout::kReport)));
  EXPECT_TRUE(report["complete"].get<bool>());
  EXPECT_EQ(report["frames"], 12);
  EXPECT_EQ(report["surfels"]["count"], s.surfels);
  // The page: its sections, and links to the files that are there.
  const std::string page = ReadTextFile(run.Path(RunLayout::kPage));
  for (const char* section : {"Trajectory", "The model", "Stereo fill", "Time per stage",
                              "Settings and files", RunLayout::kMesh})
    EXPECT_NE(page.find(section), std::string::npos) << section;
}

}  // namespace
}  // namespace gf
