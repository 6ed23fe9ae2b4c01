#include "acquisition/camera.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <random>

#include "acquisition/errors.h"
#include "acquisition/frame_source.h"
#include "tests/testing.h"

namespace gf {
namespace {

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(Camera, LoadsTheTumCameraJson) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  const CameraFile f = LoadCameraFile(tum + "/camera.json");
  EXPECT_EQ(f.camera.width, 640);
  EXPECT_EQ(f.camera.height, 480);
  EXPECT_DOUBLE_EQ(f.camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(f.camera.cy, 255.3);
  EXPECT_DOUBLE_EQ(f.camera.distortion[4], 1.1633);
  EXPECT_DOUBLE_EQ(f.depth_scale, 5000.0);
  EXPECT_TRUE(f.depth_registered_to_color);
}

TEST(Camera, JsonRoundTripKeepsEveryField) {
  testing::TempDir dir;
  CameraFile f;
  f.camera = testing::TumFr1Camera().Scaled(0.5);  // 320x240
  f.depth_scale = 1000.0;
  f.depth_registered_to_color = false;
  Camera ir = testing::TumFr1Camera();
  ir.fx = 580.5;
  f.depth_camera = ir;
  f.color_from_depth =
      SE3::Exp((SE3::Tangent() << 0.025, 0.001, -0.002, 0.01, -0.02, 0.005).finished());
  SaveCameraFile(dir / "camera.json", f);
  const CameraFile g = LoadCameraFile(dir / "camera.json");
  EXPECT_EQ(g.camera.width, 320);
  EXPECT_EQ(g.camera.height, 240);
  EXPECT_EQ(g.camera.fx, f.camera.fx);
  EXPECT_EQ(g.camera.fy, f.camera.fy);
  EXPECT_EQ(g.camera.cx, f.camera.cx);
  EXPECT_EQ(g.camera.cy, f.camera.cy);
  EXPECT_EQ(g.camera.distortion, f.camera.distortion);
  EXPECT_EQ(g.depth_scale, 1000.0);
  EXPECT_FALSE(g.depth_registered_to_color);
  ASSERT_TRUE(g.depth_camera.has_value());
  EXPECT_EQ(g.depth_camera->fx, 580.5);
  EXPECT_LT((g.color_from_depth.Matrix() - f.color_from_depth.Matrix()).norm(), 1e-12);
}

TEST(Camera, UnregisteredDepthNeedsADepthCamera) {
  testing::TempDir dir;
  std::ofstream(dir / "camera.json") << R"({"width": 640, "height": 480, "fx": 525, "fy": 525,
      "cx": 319.5, "cy": 239.5, "depth_registered_to_color": false})";
  try {
    LoadCameraFile(dir / "camera.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(e.problem().find("\"depth_camera\" intrinsics are missing"), std::string::npos)
        << e.what();
  }
}

TEST(Camera, TheDepthSensorsReadoutIsOptionalAndChecked) {
  testing::TempDir dir;
  const std::string path = dir / "camera.json";
  const std::string intrinsics =
      R"("width": 640, "height": 480, "fx": 525, "fy": 525, "cx": 319.5, "cy": 239.5)";
  WriteText(path, "{" + intrinsics + "}");
  CameraFile f = LoadCameraFile(path);
  EXPECT_FALSE(f.depth_readout_s.has_value());
  EXPECT_FALSE(f.depth_readout_order.has_value());
  WriteText(path, "{" + intrinsics +
                      R"(, "depth_readout_s": 0.02, "depth_readout_order": "right_to_left"})");
  f = LoadCameraFile(path);
  EXPECT_DOUBLE_EQ(f.depth_readout_s.value_or(-1), 0.02);
  EXPECT_EQ(f.depth_readout_order, ReadoutOrder::kRightToLeft);
  SaveCameraFile(path, f);
  EXPECT_DOUBLE_EQ(LoadCameraFile(path).depth_readout_s.value_or(-1), 0.02);
  WriteText(path, "{" + intrinsics + R"(, "depth_readout_s": -1})");
  EXPECT_THROW(LoadCameraFile(path), InputError);
  WriteText(path, "{" + intrinsics + R"(, "depth_readout_order": "diagonal"})");
  EXPECT_THROW(LoadCameraFile(path), InputError);
}

TEST(Camera, BadFilesGiveOneLineErrorsNamingFileAndProblem) {
  testing::TempDir dir;
  const std::string path = dir / "camera.json";
  auto expect_error = [&](const std::string& text, const std::string& needle) {
    WriteText(path, text);
    try {
      LoadCameraFile(path);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expect_error("{ not json", "not valid JSON");
  expect_error(R"({"width": 640, "height": 480, "fx": 525, "fy": 525, "cx": 319.5})", "\"cy\"");
  expect_error(R"({"width": 640, "height": 480, "fx": -5, "fy": 525, "cx": 1, "cy": 1})", "focal");
  expect_error(R"({"width": 640, "height": 480, "fx": 525, "fy": 525, "cx": 319.5, "cy": 239.5,
                   "depth_scale": 0})",
               "depth_scale");
  expect_error(R"({"width": "640", "height": 480, "fx": 5, "fy": 5, "cx": 1, "cy": 1})", "number");
  EXPECT_THROW(LoadCameraFile(dir / "missing.json"), InputError);
}

// Intrinsics no real camera has are refused, naming the field: the problem LoadCameraFile reports
// for a 640x480 camera.json with `fields` changed from TUM-like values.
std::string CameraProblem(const std::string& fields) {
  testing::TempDir dir;
  const std::string base =
      R"("width": 640, "height": 480, "fx": 525, "fy": 525, "cx": 319.5, "cy": 239.5)";
  WriteText(dir / "camera.json", "{" + base + (fields.empty() ? "" : ", " + fields) + "}");
  try {
    LoadCameraFile(dir / "camera.json");
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir / "camera.json");
    return e.problem();
  }
  return "";
}

TEST(Camera, ImplausibleIntrinsicsAreRefusedNamingTheField) {
  EXPECT_EQ(CameraProblem(""), "");
  // nlohmann keeps the last of duplicate keys: each case overrides a field of the base.
  EXPECT_EQ(CameraProblem(R"("fx": 1e30, "fy": 1e30)"),
            "fx 1e+30 gives a 0.0 degree field of view; expected 20-170");
  EXPECT_EQ(CameraProblem(R"("fy": 1)"),
            "fy 1 gives a 179.5 degree field of view; expected 20-170");
  EXPECT_EQ(CameraProblem(R"("fx": 3000)"),
            "fx 3000 gives a 12.2 degree field of view; expected 20-170");
  EXPECT_EQ(CameraProblem(R"("cx": 5000)"),
            "cx 5000 lies outside the image (-0.5 to 639.5 pixels)");
  EXPECT_EQ(CameraProblem(R"("cy": -20)"), "cy -20 lies outside the image (-0.5 to 479.5 pixels)");
  EXPECT_EQ(CameraProblem(R"("width": 30000, "height": 30000)"),
            "width 30000 is larger than any image (at most 4096)");
  EXPECT_EQ(CameraProblem(R"("width": 1, "height": 1, "cx": 0, "cy": 0, "fx": 1, "fy": 1)"),
            "width 1 and height 1 make an image smaller than the least GlassFusion works on "
            "(32x24)");
  // Distortion that folds back inside the image: pixels beyond the fold have no ray.
  EXPECT_EQ(CameraProblem(R"("distortion": [-10, 0, 0, 0, 0])"),
            "distortion [-10, 0, 0, 0, 0]: its radial part stops growing at normalised radius "
            "0.183, inside the image (its corners lie at 0.762): pixels beyond have no ray");
  const std::string barrel = CameraProblem(R"("distortion": [-0.5, 0, 0, 0, 0])");
  EXPECT_EQ(barrel.rfind("distortion [-0.5, 0, 0, 0, 0]: its radial part stops growing", 0), 0u)
      << barrel;
  // The depth camera of unregistered depth is held to the same, named as such.
  const std::string depth_camera = CameraProblem(
      R"("depth_registered_to_color": false, "depth_camera": {"width": 640, "height": 480,
         "fx": 580, "fy": 580, "cx": 7000, "cy": 239.5})");
  EXPECT_EQ(depth_camera, "depth_camera.cx 7000 lies outside the image (-0.5 to 639.5 pixels)");
}

// Every camera GlassFusion ships or reads is plausible: TUM fr1's strong distortion, the nominal
// Kinect v1 calibration (colour and IR), and the datasets' camera.json files.
TEST(Camera, RealCamerasArePlausible) {
  std::string problem;
  EXPECT_TRUE(testing::TumFr1Camera().CheckPlausible(&problem)) << problem;
  const CameraFile kinect = NominalKinectV1Calibration();
  EXPECT_TRUE(kinect.camera.CheckPlausible(&problem)) << problem;
  ASSERT_TRUE(kinect.depth_camera.has_value());
  EXPECT_TRUE(kinect.depth_camera->CheckPlausible(&problem)) << problem;
  EXPECT_TRUE(testing::AzureKinectNfovDepthCamera().CheckPlausible(&problem)) << problem;
  EXPECT_TRUE(testing::AzureKinect720pColorCamera().CheckPlausible(&problem)) << problem;
  int read = 0;
  for (const char* name :
       {"tum_fr1_xyz_head", "tum_fr1_xyz_mid", "icl_livingroom1_micro", "icl_livingroom1_noisy5"}) {
    const std::string folder = testing::SharedDataset(name);
    if (folder.empty()) continue;
    EXPECT_NO_THROW(LoadCameraFile(folder + "/camera.json")) << name;
    ++read;
  }
  if (read == 0) GTEST_SKIP() << "no shared datasets on this machine";
}

TEST(Camera, BackProjectInvertsProject) {
  const Camera c = testing::TumFr1Camera();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 639), v(0, 479), z(0.4, 6.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d pixel(u(rng), v(rng));
    const double depth = z(rng);
    const Eigen::Vector3d p = c.BackProject(pixel, depth);
    EXPECT_NEAR(p.z(), depth, 1e-12);
    EXPECT_LT((c.Project(p) - pixel).norm(), 1e-9);
  }
  // The principal point lies on the optical axis.
  EXPECT_LT((c.BackProject({c.cx, c.cy}, 2.0) - Eigen::Vector3d(0, 0, 2.0)).norm(), 1e-12);
}

TEST(Camera, DistortedProjectionMatchesOpenCv) {
  const Camera c = testing::TumFr1Camera();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-0.5, 0.5), z(0.5, 4.0);
  std::vector<cv::Point3d> points;
  for (int i = 0; i < 200; ++i) points.emplace_back(xy(rng), xy(rng) * 0.8, z(rng));
  std::vector<cv::Point2d> expected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), c.CvK(), c.CvDistortion(),
                    expected);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d got = c.ProjectDistorted({points[i].x, points[i].y, points[i].z});
    EXPECT_NEAR(got.x(), expected[i].x, 1e-6);
    EXPECT_NEAR(got.y(), expected[i].y, 1e-6);
  }
}

// The rational model (k4-k6) of the Azure Kinect's lenses, as OpenCV projects it, and its inverse
// over every part of the image.
TEST(Camera, RationalModelMatchesOpenCvAndInvertsOverTheImage) {
  for (const Camera& c :
       {testing::AzureKinectNfovDepthCamera(), testing::AzureKinect720pColorCamera()}) {
    std::vector<cv::Point3d> points;
    for (double x = -0.7; x <= 0.7; x += 0.1)
      for (double y = -0.6; y <= 0.6; y += 0.1) points.emplace_back(x * 2, y * 2, 2.0);
    std::vector<cv::Point2d> expected;
    cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), c.CvK(), c.CvDistortion(),
                      expected);
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector2d got = c.ProjectDistorted({points[i].x, points[i].y, points[i].z});
      EXPECT_NEAR(got.x(), expected[i].x, 1e-6);
      EXPECT_NEAR(got.y(), expected[i].y, 1e-6);
    }
    // Every pixel's ray projects back onto it, corners included.
    for (int v = 0; v < c.height; v += 16)
      for (int u = 0; u < c.width; u += 16) {
        const Eigen::Vector2d ray = c.UndistortPixel({u, v});
        const Eigen::Vector2d back = c.ProjectDistorted({ray.x(), ray.y(), 1.0});
        EXPECT_LT((back - Eigen::Vector2d(u, v)).norm(), 1e-6) << c.width << ": " << u << "," << v;
      }
  }
}

// camera.json keeps 8 coefficients when k4-k6 are not zero, and writes 5 when they are.
TEST(Camera, JsonKeepsTheRationalModel) {
  testing::TempDir dir;
  CameraFile f;
  f.camera = testing::AzureKinect720pColorCamera();
  f.depth_scale = 1000.0;
  SaveCameraFile(dir / "camera.json", f);
  EXPECT_EQ(LoadCameraFile(dir / "camera.json").camera.distortion, f.camera.distortion);
  f.camera = testing::TumFr1Camera();
  SaveCameraFile(dir / "camera.json", f);
  std::ifstream in(dir / "camera.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["distortion"].size(), 5u);
  EXPECT_EQ(LoadCameraFile(dir / "camera.json").camera.distortion, f.camera.distortion);
}

TEST(Camera, UndistortInvertsDistortOverTheImage) {
  const Camera c = testing::TumFr1Camera();
  for (double x = -0.55; x <= 0.55; x += 0.05) {
    for (double y = -0.45; y <= 0.45; y += 0.05) {
      const Eigen::Vector2d n(x, y);
      EXPECT_LT((c.Undistort(c.Distort(n)) - n).norm(), 1e-9) << x << "," << y;
      // UndistortPixel inverts ProjectDistorted.
      const Eigen::Vector2d pixel = c.ProjectDistorted({x * 2.0, y * 2.0, 2.0});
      EXPECT_LT((c.UndistortPixel(pixel) - n).norm(), 1e-9) << x << "," << y;
    }
  }
}

TEST(Camera, ScaledCameraSeesTheSamePointAtTheScaledPixel) {
  const Camera c = testing::TumFr1Camera();
  const Camera half = c.Scaled(0.5);
  EXPECT_EQ(half.width, 320);
  EXPECT_EQ(half.height, 240);
  const Eigen::Vector3d p(0.3, -0.2, 1.7);
  const Eigen::Vector2d full = c.Project(p);
  const Eigen::Vector2d small = half.Project(p);
  // Pixel centres: small = (full + 0.5) / 2 - 0.5.
  EXPECT_LT((small - ((full.array() + 0.5) * 0.5 - 0.5).matrix()).norm(), 1e-9);
}

}  // namespace
}  // namespace gf
