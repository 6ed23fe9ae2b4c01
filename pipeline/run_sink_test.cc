// FolderRunSink's run folder: --force (replace) removes only what an earlier run wrote, never a
// folder that holds no run (a capture has a camera.json too), and a second sink into a folder a
// live sink is writing is refused at once. RunReader reads back what it wrote. CompleteFromModel:
// what the map may complete.
#include "pipeline/run_sink.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "pipeline/run_reader.h"
#include "tests/testing.h"

namespace gf {
namespace {

namespace fs = std::filesystem;

void Touch(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << text;
}

RunReport Complete() {
  RunReport report;
  report.complete = true;
  return report;
}

// A report with every section: each kind of field set to something other than its default.
RunReport Rich() {
  RunReport r = Complete();
  r.input = {"capture", "tum", 2, 40};
  r.config.stereo_fill = r.config.surfel_fusion = r.config.loop_closure = true;
  r.config.file = "settings.json";
  r.config.settings = {{"fill", {{"pairs", {{"lookahead", 3}}}}}};
  r.frames = 1;
  r.fps = 12.5;
  r.stages.steps = {{"read", StepTimes::Of({1.5, 2.5})}, {"stereo", StepTimes::Of({})}};
  r.stages.cpu_seconds = CpuSecondsReport{{{"read", 0.25}, {"fill", 1.0}}, 0.5, 1.75, 0.9, 2};
  r.stages.peak_resident_mib = 300.5;
  r.tracking.lost = {"1.5"};
  r.loops.enabled = true;
  r.loops.refused = {{"too few inliers", 2}};
  r.loops.loops = {{"5.0", "1.0", true}};
  KeyframeFill k;
  k.timestamp = "1.5";
  k.partner = "2.5";
  k.path = "plane_sweep_forward";
  k.hole_pixels = 10;
  k.filled_pixels = 4;
  r.fill = FillReport::Of({k}, 1, 0);
  r.fill->model_completion = ModelCompletionReport{1, 3, 0.5, false, 1, 1, 0, 0};
  r.surfels = SurfelReport();
  r.surfels->by_source = {{"sensor", 7}, {"stereo_fill", 2}};
  r.surfels->count_over_time = {{10, 9, 7, 2, 1}};
  r.surfels->first_failure = "a test";
  r.surfels->glass_objects = 3, r.surfels->glass_shapes = 2, r.surfels->glass_shape_surfels = 1234;
  r.warnings = {"a warning"};
  return r;
}

// What a run writes without any frames: its report and an empty map.
void WriteSomething(RunSink* sink) {
  sink->WriteReport(Complete());
  sink->WriteMap({});
}

// The message of the InputError that constructing FolderRunSink(dir, replace) throws ("" when
// none).
std::string Refusal(const std::string& dir, bool replace) {
  try {
    FolderRunSink sink(dir, replace);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A capture (camera.json, depth.txt, frames, the user's notes): --force must not touch it.
// What the folder sink writes, the reader reads back through the same names.
TEST(RunReader, ReadsBackWhatTheFolderSinkWrote) {
  testing::TempDir dir;
  const std::string run = dir / "run";
  {
    FolderRunSink sink(run, false);
    CameraFile camera;
    camera.camera = testing::PinholeCamera(64, 48, 50);
    sink.WriteCamera(camera);
    sink.WriteTrajectory({{1.5, "1.500000", SE3(Eigen::Matrix3d::Identity(), {0.1, 0.2, 0.3})}});
    Surfel s{};
    s.position = {1, 2, 3};
    s.normal = {0, 0, -1};
    s.radius = 0.01f;
    s.confidence = 5;
    sink.WriteMap({s, s});
    sink.WriteReport(Rich());
  }
  const RunReader reader(run);
  // report.json reads back as the report written, every field.
  EXPECT_EQ(nlohmann::ordered_json(reader.Report()).dump(2), nlohmann::ordered_json(Rich()).dump(2));
  ASSERT_EQ(reader.Poses().size(), 1u);
  EXPECT_EQ(reader.Poses()[0].timestamp_text, "1.500000");
  EXPECT_NEAR(reader.Poses()[0].world_from_camera.translation().z(), 0.3, 1e-9);
  EXPECT_EQ(reader.ImageCamera().width, 64);
  ASSERT_EQ(reader.Map().size(), 2u);
  EXPECT_FLOAT_EQ(reader.Map()[1].position.y(), 2.0f);
  EXPECT_TRUE(reader.Has(RunLayout::kMap));
  EXPECT_FALSE(reader.Has(RunLayout::kMesh));  // written only with --mesh
  EXPECT_THROW(RunReader(dir / "none").Report(), InputError);
}

TEST(FolderRunSink, ForceNeverEmptiesACapture) {
  testing::TempDir dir;
  const std::string cap = dir / "cap";
  for (const char* f : {"camera.json", "depth.txt", "rgb.txt", "depth/1.png", "NOTES.txt"})
    Touch(cap + "/" + f, "user data");
  const std::string why = Refusal(cap, true);
  EXPECT_NE(why.find("holds no run"), std::string::npos) << why;
  for (const char* f : {"camera.json", "depth.txt", "rgb.txt", "depth/1.png", "NOTES.txt"})
    EXPECT_EQ(ReadTextFile(cap + "/" + f), "user data") << f;
}

// --force over an earlier run removes that run's files and keeps the user's files beside them,
// even inside a folder the run made.
TEST(FolderRunSink, ForceRemovesOnlyWhatTheEarlierRunWrote) {
  testing::TempDir dir;
  const std::string run = dir / "run";
  {
    FolderRunSink sink(run, false);
    WriteSomething(&sink);
  }
  Touch(run + "/notes.txt", "mine");
  Touch(run + "/undistorted/mine.txt", "mine too");
  EXPECT_NE(Refusal(run, false).find("--force"), std::string::npos);
  {
    FolderRunSink sink(run, true);
    EXPECT_FALSE(fs::exists(run + "/report.json")) << "the earlier run's report is still there";
    EXPECT_FALSE(fs::exists(run + "/map.ply"));
    EXPECT_EQ(ReadTextFile(run + "/notes.txt"), "mine");
    EXPECT_EQ(ReadTextFile(run + "/undistorted/mine.txt"), "mine too");
    WriteSomething(&sink);
  }
  EXPECT_TRUE(fs::exists(run + "/report.json"));
}

// A file the run did not write is never overwritten, even in a folder that holds a run.
TEST(FolderRunSink, NeverOverwritesAFileItDidNotWrite) {
  testing::TempDir dir;
  const std::string run = dir / "run";
  {
    FolderRunSink sink(run, false);
    sink.WriteReport(Complete());
  }
  Touch(run + "/map.ply", "the user's own model");
  FolderRunSink sink(run, true);
  EXPECT_THROW(sink.WriteMap({}), InputError);
  EXPECT_EQ(ReadTextFile(run + "/map.ply"), "the user's own model");
}

// While one sink writes a folder, a second one (with or without replace) is refused and deletes
// nothing of the first's.
TEST(FolderRunSink, ASecondRunIntoALiveFolderIsRefused) {
  testing::TempDir dir;
  const std::string run = dir / "run";
  FolderRunSink first(run, false);
  WriteSomething(&first);
  for (bool replace : {false, true}) {
    const std::string why = Refusal(run, replace);
    EXPECT_NE(why.find("another glassfusion run is writing here"), std::string::npos) << why;
  }
  EXPECT_TRUE(fs::exists(run + "/report.json"));
  EXPECT_TRUE(fs::exists(run + "/map.ply"));
}

}  // namespace
}  // namespace gf

namespace gf {
namespace {

// The map's offer completes a keyframe's holes only where nothing of the keyframe hides it: a
// sensor pixel near the hole that lies in front of the offered depth (the hole's rim belongs to
// a nearer object) keeps the map's farther surface out; the completed pixels take the offer's
// confidence; measured pixels and projector shadows never change.
TEST(CompleteFromModel, TheMapFillsOnlyHolesThatNothingNearerHides) {
  const cv::Size size(40, 20);
  cv::Mat holes = cv::Mat::zeros(size, CV_8UC1);
  cv::Mat depth(size, CV_32FC1, cv::Scalar(2.0));  // the sensor: a wall at 2 m...
  depth(cv::Rect(0, 0, 10, 20)) = 1.0;             // ... and a near object on the left
  // Two holes: one beside the near object (x 10-13), one in the middle of the wall (x 24-27);
  // a shadow at x 34.
  for (int x : {10, 11, 12, 13, 24, 25, 26, 27}) holes.col(x) = 1;
  holes.col(34) = static_cast<uint8_t>(HoleCode::kShadow);
  depth.setTo(0.f, holes != 0);
  MapCompletion offer;
  offer.depth = cv::Mat(size, CV_32FC1, cv::Scalar(2.0));  // the map: the wall everywhere
  offer.confidence = cv::Mat(size, CV_32FC1, cv::Scalar(0.6));
  offer.occluder_px = 3;
  offer.occluder_margin = 0.03;
  cv::Mat filled = depth.clone(), confidence = cv::Mat::zeros(size, CV_32FC1), completed;
  const int n = CompleteFromModel(holes, offer, &filled, &confidence, &completed);
  // Beside the near object, the three columns within 3 px of it stay empty; the fourth and the
  // whole middle hole are completed.
  EXPECT_EQ(n, 5 * size.height);
  for (int x : {10, 11, 12}) EXPECT_EQ(cv::countNonZero(completed.col(x)), 0) << x;
  for (int x : {13, 24, 25, 26, 27}) EXPECT_EQ(cv::countNonZero(completed.col(x)), size.height);
  EXPECT_EQ(cv::countNonZero(completed.col(34)), 0);  // a shadow
  EXPECT_EQ(cv::norm(filled, depth, cv::NORM_INF, holes == 0), 0.0);  // measured: unchanged
  EXPECT_FLOAT_EQ(confidence.at<float>(5, 25), 0.6f);
  EXPECT_FLOAT_EQ(confidence.at<float>(5, 11), 0.f);
  // Without the check, the hole beside the near object is completed too.
  offer.occluder_px = 0;
  filled = depth.clone();
  EXPECT_EQ(CompleteFromModel(holes, offer, &filled, nullptr, &completed), 8 * size.height);
}

}  // namespace
}  // namespace gf
