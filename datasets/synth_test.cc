#include "datasets/synth.h"

#include <gtest/gtest.h>
#include <pcl/PolygonMesh.h>
#include <pcl/io/ply_io.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "acquisition/errors.h"
#include "acquisition/frame_source.h"
#include "acquisition/trajectory.h"
#include "tests/testing.h"

namespace gf::synth {
namespace {

namespace fs = std::filesystem;

// One frame of the glass-table scene, rendered once for all sensor-model tests.
const SynthFrame& TableFrame() {
  static const SynthFrame frame = [] {
    SynthOptions options;
    options.frames = 30;
    const Scene scene = Scene::Make("glass-table", 7);
    const std::vector<SE3> poses = MakeTrajectory(scene, options);
    return RenderFrame(scene, SynthCamera(), poses[5], options.kinect, 7, 5);
  }();
  return frame;
}

bool InRange(float z) { return z >= 0.5f && z <= 4.5f; }

TEST(KinectModel, IrFailingMaterialsAreHolesAndDiffuseSurfacesAreMeasured) {
  const SynthFrame& f = TableFrame();
  std::map<int, std::pair<int, int>> per_material;  // label -> (holes, pixels), in range
  int diffuse_no_return = 0, diffuse_shadow = 0;
  for (int v = 0; v < f.label.rows; ++v) {
    for (int u = 0; u < f.label.cols; ++u) {
      const int label = f.label.at<uint8_t>(v, u);
      if (label == kNoSurface || !InRange(f.true_depth.at<float>(v, u))) continue;
      const bool hole = f.raw_disparity.at<uint16_t>(v, u) == 2047;
      per_material[label].first += hole;
      per_material[label].second += 1;
      const uint8_t reason = f.hole_reason.at<uint8_t>(v, u);
      if (label == 0 && reason == static_cast<uint8_t>(HoleCode::kNoReturn)) ++diffuse_no_return;
      if (label == 0 && reason == static_cast<uint8_t>(HoleCode::kShadow)) ++diffuse_shadow;
    }
  }
  for (Material m :
       {Material::kGlossy, Material::kDark, Material::kTexturedGlass, Material::kClearGlass}) {
    const auto [holes, pixels] = per_material[static_cast<int>(m)];
    ASSERT_GT(pixels, 300) << MaterialName(m) << " barely visible";
    EXPECT_GT(static_cast<double>(holes) / pixels, 0.90) << MaterialName(m);
  }
  const auto [holes, pixels] = per_material[0];
  // Diffuse surfaces in range: no-return holes only at grazing angles, under 2%. Projector
  // shadows are a separate class (geometry, not material) and counted apart.
  EXPECT_LT(static_cast<double>(diffuse_no_return) / pixels, 0.02);
  EXPECT_LT(static_cast<double>(holes - diffuse_shadow) / pixels, 0.02);
  RecordProperty("diffuse_shadow_fraction",
                 std::to_string(static_cast<double>(diffuse_shadow) / pixels));
}

TEST(KinectModel, DepthErrorFollowsTheNoiseModel) {
  const SynthFrame& f = TableFrame();
  const KinectModelOptions k;
  const DepthConvention raw_model = DepthConvention::KinectV1Raw11Bit();
  // Bins of true depth; in each the error's mean and spread against sigma(z) and quantisation.
  struct Bin {
    double sum = 0, sum2 = 0, expected_var = 0;
    int n = 0;
  };
  std::map<int, Bin> bins;
  for (int v = 0; v < f.label.rows; ++v) {
    for (int u = 0; u < f.label.cols; ++u) {
      const uint16_t raw = f.raw_disparity.at<uint16_t>(v, u);
      if (raw == 2047 || f.label.at<uint8_t>(v, u) != 0) continue;
      const double z = f.true_depth.at<float>(v, u);
      const double err = raw_model.ToMetres(raw) - z;
      const double sigma = k.noise_a_m + k.noise_b_per_m * (z - 0.4) * (z - 0.4);
      const double step = z * z * std::abs(DepthConvention::kKinectA);  // one raw unit at z
      Bin& b = bins[static_cast<int>(z * 2)];                           // 0.5 m bins
      b.sum += err;
      b.sum2 += err * err;
      b.expected_var += sigma * sigma + step * step / 12.0;
      ++b.n;
    }
  }
  int checked = 0;
  for (const auto& [key, b] : bins) {
    if (b.n < 2000) continue;
    const double mean = b.sum / b.n, rms = std::sqrt(b.sum2 / b.n);
    const double expected = std::sqrt(b.expected_var / b.n);
    EXPECT_LT(std::abs(mean), 0.25 * expected) << "bin " << key * 0.5 << " m";
    EXPECT_NEAR(rms / expected, 1.0, 0.15) << "bin " << key * 0.5 << " m";
    ++checked;
  }
  EXPECT_GE(checked, 2);
}

TEST(KinectModel, ShadowsLieLeftOfNearerSurfacesAndAcquisitionFindsThem) {
  const SynthFrame& f = TableFrame();
  const uint8_t shadow = static_cast<uint8_t>(HoleCode::kShadow);
  int shadows = 0, nearer_on_right = 0;
  for (int v = 0; v < f.label.rows; ++v) {
    for (int u = 0; u < f.label.cols; ++u) {
      if (f.hole_reason.at<uint8_t>(v, u) != shadow) continue;
      ++shadows;
      // The occluder is to the right (towards the projector at +x): within 60 px the first
      // non-shadow pixel is nearer.
      for (int x = u + 1; x < std::min(f.label.cols, u + 60); ++x) {
        if (f.hole_reason.at<uint8_t>(v, x) == shadow) continue;
        nearer_on_right += f.true_depth.at<float>(v, x) < 0.97f * f.true_depth.at<float>(v, u);
        break;
      }
    }
  }
  ASSERT_GT(shadows, 1000);
  EXPECT_GT(static_cast<double>(nearer_on_right) / shadows, 0.95);
  // acquisition's ClassifyShadows, which knows nothing of the renderer, recovers most of them.
  cv::Mat depth, holes;
  ConvertDepth(f.raw_disparity, DepthConvention::KinectV1Raw11Bit(), {}, &depth, &holes);
  ClassifyShadows(depth, SynthCamera().fx, ShadowOptions{}, &holes);
  int found = 0, claimed = 0, claimed_right = 0;
  for (int v = 0; v < holes.rows; ++v) {
    for (int u = 0; u < holes.cols; ++u) {
      const bool truth = f.hole_reason.at<uint8_t>(v, u) == shadow;
      const bool said = holes.at<uint8_t>(v, u) == shadow;
      found += truth && said;
      claimed += said;
      claimed_right += said && truth;
    }
  }
  EXPECT_GT(static_cast<double>(found) / shadows, 0.6);
  EXPECT_GT(static_cast<double>(claimed_right) / claimed, 0.9);
}

TEST(Trajectory, LoopComesBackToItsStart) {
  SynthOptions options;
  options.frames = 120;
  options.loop = true;
  const Scene scene = Scene::Make("glass-table", 3);
  const std::vector<SE3> poses = MakeTrajectory(scene, options);
  const double step = (poses[1].translation() - poses[0].translation()).norm();
  EXPECT_GT(step, 0.02);
  // One step after the last frame is the first frame again.
  EXPECT_LT((poses.back().translation() - poses.front().translation()).norm(), 2.0 * step);
  // Every camera looks at the table from inside the room.
  for (const SE3& p : poses) {
    const Eigen::Vector3d forward = p.RotationMatrix().col(2);
    EXPECT_GT(forward.dot((scene.focus() - p.translation()).normalized()), 0.98);
  }
}

// Each motion moves the camera, seen from its own frame, the way its name says (the handheld
// wobble off), at the same distance per frame.
TEST(Trajectory, EachMotionMovesTheCameraAlongItsAxis) {
  const Scene scene = Scene::Make("glass-table", 3);
  // The share of the motion along the camera's x (right), y (down) and z (forward) axes.
  auto share = [&](const std::string& motion) {
    SynthOptions options;
    options.frames = 30;
    options.jitter_m = 0;
    options.motion = motion;
    const std::vector<SE3> poses = MakeTrajectory(scene, options);
    const SE3& a = poses[14];
    const Eigen::Vector3d step =
        a.RotationMatrix().transpose() * (poses[15].translation() - a.translation());
    EXPECT_NEAR(step.norm(), scene.orbit_radius() * 0.6 * M_PI / 180.0, 1e-3) << motion;
    return Eigen::Vector3d(step.cwiseAbs() / step.norm());
  };
  EXPECT_GT(share("orbit").x(), 0.99);
  EXPECT_GT(share("vertical").y(), 0.9);
  EXPECT_GT(share("forward").z(), 0.99);
  const Eigen::Vector3d diagonal = share("diagonal");
  EXPECT_NEAR(diagonal.x(), diagonal.y(), 0.15);
  SynthOptions bad;
  bad.motion = "sideways";
  EXPECT_FALSE(bad.Check());
}

std::map<std::string, std::string> ReadAll(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    files[fs::relative(e.path(), dir).string()] =
        std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  return files;
}

TEST(GenerateDataset, SameSeedSameBytesAndReadableByEveryReader) {
  testing::TempDir dir;
  SynthOptions options;
  options.scene = "shelf";
  options.frames = 2;
  options.seed = 42;
  const SynthSummary a = GenerateDataset(options, dir / "a");
  GenerateDataset(options, dir / "b");
  options.seed = 43;
  GenerateDataset(options, dir / "c");
  auto files_a = ReadAll(dir / "a"), files_b = ReadAll(dir / "b"), files_c = ReadAll(dir / "c");
  EXPECT_EQ(files_a.size(), files_b.size());
  // Only synth.json differs between runs (it records the generation time).
  files_a.erase("synth.json");
  files_b.erase("synth.json");
  for (const auto& [name, bytes] : files_a) EXPECT_TRUE(files_b[name] == bytes) << name;
  EXPECT_NE(files_a["rgb/0.000000.png"], files_c["rgb/0.000000.png"]);
  EXPECT_EQ(files_a.count("gt/label/0.033333.png"), 1u);
  EXPECT_EQ(files_a.count("raw/d-0.033333-1.pgm"), 1u);

  // The TUM folder and the fakenect recording read back with the same holes.
  for (const std::string& input : {dir / "a", dir / "a/raw"}) {
    auto source = OpenFrameSource(input, {});
    EXPECT_EQ(source->FrameCount().value(), 2) << input;
    RgbdFrame frame;
    HoleStats holes;
    while (source->Next(&frame)) holes += frame.sensor_holes;
    EXPECT_NEAR(holes.Fraction(), a.hole_fraction, 1e-9) << input;
  }
  // Ground truth trajectory and scene mesh: standard readers.
  EXPECT_EQ(ReadTumTrajectory(dir / "a/groundtruth.txt").size(), 2u);
  pcl::PolygonMesh mesh;
  ASSERT_EQ(pcl::io::loadPLYFile(dir / "a/scene.ply", mesh), 0);
  EXPECT_GT(mesh.polygons.size(), 1000u);
  // Every face indexes an existing vertex; the room spans 6 x 5 x 2.8 m.
  const size_t vertices = mesh.cloud.width * mesh.cloud.height;
  for (const auto& face : mesh.polygons)
    for (uint32_t index : face.vertices) ASSERT_LT(index, vertices);
  // Refuses a non-empty folder and leaves nothing behind.
  EXPECT_THROW(GenerateDataset(options, dir / "a"), InputError);
  EXPECT_FALSE(fs::exists(dir / "c.partial-" + std::to_string(::getpid())));
}

}  // namespace
}  // namespace gf::synth
