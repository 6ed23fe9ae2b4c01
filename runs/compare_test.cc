// `compare` in-process on a synthetic glass capture (no datasets needed; seed 11, never used for
// tuning): both run folders complete, the map with the fill covers the glossy, dark and
// textured-glass surfaces far better than the sensor's alone, and its filled surfels lie on the
// true surfaces. (tests/cli_compare_glass.cmake checks the command line's side: the files, `eval
// --map` agreeing with compare.json, map.ply and mesh.ply read back by Open3D.)
#include "runs/compare.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "acquisition/file_util.h"
#include "datasets/synth.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

TEST(Compare, TheFillCompletesTheSurfacesTheSensorMisses) {
  testing::TempDir tmp;
  synth::SynthOptions scene;
  scene.frames = 30;
  scene.seed = 11;
  synth::GenerateDataset(scene, tmp / "scene");
  ReconstructOptions options;
  options.input = tmp / "scene";
  options.out_dir = tmp / "cmp";
  const CompareSummary s = RunCompare(options);
  EXPECT_TRUE(s.run.complete);
  EXPECT_EQ(s.run.frames, 30);
  for (const char* f : {"compare.json", "report.html", "with_fill/map.ply", "with_fill/report.json",
                        "without_fill/map.ply", "without_fill/report.json",
                        "with_fill_camera.png", "without_fill_above.png"})
    EXPECT_TRUE(fs::exists(fs::path(options.out_dir) / f)) << f;
  const nlohmann::ordered_json& c = s.compare;
  for (const char* material : {"glossy", "dark", "textured_glass"}) {
    const double with =
        c["with_fill"]["completeness"]["per_material"][material]["within_2cm"].get<double>();
    const double without =
        c["without_fill"]["completeness"]["per_material"][material]["within_2cm"].get<double>();
    EXPECT_GE(with, 0.6) << material;
    EXPECT_LE(without, 0.3) << material;
  }
  EXPECT_LE(c["with_fill"]["accuracy"]["fill_median_m"].get<double>(), 0.01);
  EXPECT_GT(c["with_fill"]["surfels"]["count"].get<long>(),
            c["without_fill"]["surfels"]["count"].get<long>());
  EXPECT_LT(c["ate_m"].get<double>(), 0.02);
  // The page shows both models and the completeness table with the figures of compare.json.
  const std::string page = ReadTextFile((fs::path(options.out_dir) / "report.html").string());
  EXPECT_NE(page.find("The two models"), std::string::npos);
  EXPECT_NE(page.find("2 cm, with the fill"), std::string::npos);
  EXPECT_NE(page.find("with_fill_camera.png"), std::string::npos);
}

}  // namespace
}  // namespace gf
