#include "fill/rectified_sgbm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>
#include <random>
#include <set>
#include <string>

#include "acquisition/depth.h"
#include "datasets/synth.h"
#include "fill/stereo_fill.h"
#include "tests/testing.h"

namespace gf {
namespace {

// The pair that crashed a 798-frame TUM fr1/xyz run: keyframe 2 sits (-0.032, -0.089, 0.018) m
// from keyframe 1, mostly below it, seen through TUM's lens; the desk is 0.6-3.6 m away.
// cv::stereoRectify's crop magnified it 41 times, so the search wanted 2843 disparities from 570
// on a 480-pixel-wide (transposed) image, and OpenCV's SGBM aborted the process.
TEST(RectifyForSgbm, AMostlyVerticalBaselineThroughTumsLensGetsASearchThatFits) {
  const Camera camera = testing::TumFr1Camera();
  const SE3 key1_from_key2(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.032, -0.089, 0.018));
  const SgbmOptions options;
  const SgbmRectification r = RectifyForSgbm(camera, key1_from_key2, 0.6, 3.6, options);
  SCOPED_TRACE(r.BriefReport());
  EXPECT_TRUE(r.vertical);
  EXPECT_TRUE(r.rescaled);  // the crop's magnification did not fit
  EXPECT_LT(r.zoom, 4.0);
  EXPECT_LE(r.num_disparities, options.num_disparities);
  ASSERT_TRUE(r.usable) << r.problem;
  // The transposed image is 480 wide: the search ends by half of it.
  EXPECT_TRUE(SgbmParametersFit(camera.height, camera.width, r.min_disparity, r.num_disparities,
                                options.block_size));
  // The whole depth range is searched: 0.6 m and 3.6 m both fall inside.
  EXPECT_LE(r.min_disparity, r.fb / 3.6);
  EXPECT_GE(r.min_disparity + r.num_disparities, r.fb / 0.6);
}

// A sideways pair through TUM's lens, turned 6 degrees: cv::stereoRectify's crop magnifies it.
// Limited to max_zoom, the same field of view lands on a smaller image: the images' corners look
// along the same rays, and the search shrinks with the magnification.
TEST(RectifyForSgbm, AMagnifiedCropKeepsItsFieldOfViewOnASmallerImage) {
  const Camera camera = testing::TumFr1Camera();
  const SE3 key1_from_key2(
      Eigen::AngleAxisd(6 * M_PI / 180, Eigen::Vector3d(0.2, 1, 0.1).normalized())
          .toRotationMatrix(),
      Eigen::Vector3d(-0.08, 0.01, 0.01));
  SgbmOptions unlimited;
  unlimited.max_zoom = 0;
  const SgbmRectification crop = RectifyForSgbm(camera, key1_from_key2, 0.6, 3.6, unlimited);
  SgbmOptions limited;
  limited.max_zoom = 1.0;
  const SgbmRectification r = RectifyForSgbm(camera, key1_from_key2, 0.6, 3.6, limited);
  SCOPED_TRACE(crop.BriefReport() + " / " + r.BriefReport());
  ASSERT_TRUE(crop.usable && r.usable);
  ASSERT_GT(crop.zoom, 1.1);  // the case this test is about
  EXPECT_EQ(crop.size, cv::Size(camera.width, camera.height));
  EXPECT_NEAR(r.zoom, 1.0, 0.01);
  EXPECT_NEAR(r.size.width, camera.width / crop.zoom, 1.0);
  EXPECT_NEAR(r.size.height, camera.height / crop.zoom, 1.0);
  // The rays through the images' outer corners, in the rectified camera.
  auto ray = [](const SgbmRectification& x, double u, double v) {
    const cv::Mat& p = x.p_left;
    return Eigen::Vector3d((u - p.at<double>(0, 2)) / p.at<double>(0, 0),
                           (v - p.at<double>(1, 2)) / p.at<double>(1, 1), 1.0);
  };
  for (const double fu : {0.0, 1.0})
    for (const double fv : {0.0, 1.0}) {
      const Eigen::Vector3d a = ray(crop, fu * camera.width - 0.5, fv * camera.height - 0.5);
      const Eigen::Vector3d b = ray(r, fu * r.size.width - 0.5, fv * r.size.height - 0.5);
      EXPECT_LT((a - b).norm(), 2.0 / camera.fx) << fu << " " << fv;  // within two pixels
    }
  EXPECT_NEAR(r.fb, crop.fb / crop.zoom, 1e-6 * crop.fb);
  EXPECT_LT(r.min_disparity + r.num_disparities, crop.min_disparity + crop.num_disparities);
  EXPECT_NEAR(r.valid_fraction, crop.valid_fraction, 0.05);
  // The rectified images come out at that size.
  RgbdFrame key;
  key.color = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(90, 120, 150));
  const RectifiedImages images = RectifyImages(r, key, key, camera);
  EXPECT_EQ(images.left.size(), r.size);
  EXPECT_EQ(images.valid_right.size(), r.size);
}

TEST(RectifyForSgbm, RefusesPairsSgbmCannotServe) {
  // A tiny image cannot hold the disparities of a long baseline at close range.
  Camera tiny;
  tiny.width = 24;  // half the width is less than SGBM's smallest search, 16 disparities
  tiny.height = 18;
  tiny.fx = tiny.fy = 20;
  tiny.cx = 11.5;
  tiny.cy = 8.5;
  const SE3 sideways(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.3, 0, 0));
  const SgbmRectification r = RectifyForSgbm(tiny, sideways, 0.3, 3.0, {});
  EXPECT_FALSE(r.usable);
  EXPECT_EQ(r.refusal, "disparity_range") << r.BriefReport();
  // Cameras looking 100 degrees apart share almost nothing once rectified.
  const Camera camera = synth::SynthCamera();
  const SE3 apart(Eigen::AngleAxisd(100 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix(),
                  Eigen::Vector3d(0.2, 0, 0));
  const SgbmRectification q = RectifyForSgbm(camera, apart, 0.5, 4.0, {});
  EXPECT_FALSE(q.usable) << q.BriefReport();
  EXPECT_FALSE(q.refusal.empty());
  EXPECT_FALSE(q.problem.empty());
}

TEST(SgbmParametersFit, TheSearchEndsByHalfTheWidth) {
  EXPECT_TRUE(SgbmParametersFit(640, 480, 0, 128, 5));
  EXPECT_TRUE(SgbmParametersFit(640, 480, 192, 128, 5));
  EXPECT_FALSE(SgbmParametersFit(640, 480, 193, 128, 5));
  EXPECT_FALSE(SgbmParametersFit(480, 640, 570, 128, 5));  // the crash's search
  EXPECT_FALSE(SgbmParametersFit(640, 480, -1, 128, 5));
  EXPECT_FALSE(SgbmParametersFit(640, 480, 0, 100, 5));  // not a multiple of 16
  EXPECT_FALSE(SgbmParametersFit(640, 480, 0, 128, 4));  // even block
  EXPECT_FALSE(SgbmParametersFit(64, 4, 0, 16, 5));      // block taller than the image
}

// The crash's geometry on the synthetic glass table (a pinhole camera): the vertical pair is
// rectified and searched over its whole depth range; SGBM alone (the sweep after it off, which
// would fill the holes even if SGBM gave nothing, as it did while the transposed images were
// overwritten by their masks) fills some of the holes with small errors, and with the sweep after
// it a quarter or more.
TEST(FillHolesByStereo, FillsAMostlyVerticalPair) {
  const Camera camera = synth::SynthCamera();
  synth::SynthOptions options;
  options.frames = 30;
  const synth::Scene scene = synth::Scene::Make("glass-table", 5);
  const SE3 world_from_key1 = synth::MakeTrajectory(scene, options)[10];
  const SE3 key1_from_key2(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.032, -0.089, 0.018));
  const synth::SynthFrame t1 =
      synth::RenderFrame(scene, camera, world_from_key1, synth::KinectModelOptions{}, 5, 10);
  const synth::SynthFrame t2 = synth::RenderFrame(scene, camera, world_from_key1 * key1_from_key2,
                                                  synth::KinectModelOptions{}, 5, 11);
  const RgbdFrame key1 = synth::ToRgbdFrame(t1, 10), key2 = synth::ToRgbdFrame(t2, 11);
  auto good_share = [&](const StereoFillResult& r) {
    int good = 0;
    for (int y = 0; y < key1.depth.rows; ++y)
      for (int x = 0; x < key1.depth.cols; ++x) {
        if (!r.fill_mask.at<uint8_t>(y, x)) continue;
        const double truth = t1.visible_depth.at<float>(y, x);
        good += std::abs(r.filled_depth.at<float>(y, x) - truth) <= 0.03 * truth;
      }
    return static_cast<double>(good) / std::max(1, r.filled_pixels);
  };
  StereoFillOptions sgbm_only;
  sgbm_only.plane_sweep_after_sgbm = false;
  const StereoFillResult sgbm = FillHolesByStereo(key1, key2, camera, key1_from_key2, sgbm_only);
  {
    SCOPED_TRACE(sgbm.BriefReport() + "; " + sgbm.rectification.BriefReport());
    EXPECT_EQ(sgbm.path, PairPath::kRectifiedSgbm);
    EXPECT_EQ(sgbm.method, FillMethod::kRectifiedSgbm);
    EXPECT_TRUE(sgbm.rectification.vertical);
    ASSERT_TRUE(sgbm.success);
    EXPECT_GT(sgbm.filled_pixels, sgbm.hole_pixels / 20);
    EXPECT_GT(good_share(sgbm), 0.8);
  }
  const StereoFillResult both = FillHolesByStereo(key1, key2, camera, key1_from_key2, {});
  SCOPED_TRACE(both.BriefReport());
  ASSERT_TRUE(both.success);
  EXPECT_GT(both.filled_pixels, both.hole_pixels / 4);
  EXPECT_GT(good_share(both), 0.8);
  // SGBM on images no more magnified than the camera's own pixels fills about as much, as well.
  StereoFillOptions camera_pixels = sgbm_only;
  camera_pixels.sgbm.max_zoom = 1.0;
  const StereoFillResult small =
      FillHolesByStereo(key1, key2, camera, key1_from_key2, camera_pixels);
  SCOPED_TRACE(small.BriefReport() + "; " + small.rectification.BriefReport());
  ASSERT_TRUE(small.success);
  EXPECT_LE(small.rectification.zoom, 1.0 + 1e-9);
  EXPECT_LT(small.rectification.size.area(), camera.width * camera.height);
  EXPECT_GT(small.filled_pixels, 0.8 * sgbm.filled_pixels);
  EXPECT_GT(good_share(small), 0.8);
}

// A textured frame of the given size: noise blurred into blobs, depth a tilted plane at 0.8-3 m
// with a rectangular no-return hole and a few scattered ones.
RgbdFrame RandomFrame(const Camera& camera, std::mt19937* rng) {
  RgbdFrame f;
  cv::Mat noise(camera.height, camera.width, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::GaussianBlur(noise, f.color, {5, 5}, 1.5);
  f.depth = cv::Mat(camera.height, camera.width, CV_32FC1);
  f.hole_mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  std::uniform_real_distribution<double> u(0, 1);
  const double z0 = 0.8 + 2.2 * u(*rng), slope = u(*rng) - 0.5;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x)
      f.depth.at<float>(y, x) = static_cast<float>(z0 * (1 + 0.5 * slope * y / camera.height));
  const cv::Rect hole(camera.width / 3, camera.height / 3, camera.width / 4, camera.height / 4);
  f.hole_mask(hole).setTo(static_cast<uint8_t>(HoleCode::kNoReturn));
  for (int i = 0; i < camera.width * camera.height / 50; ++i)
    f.hole_mask.at<uint8_t>(static_cast<int>(u(*rng) * (camera.height - 1)),
                            static_cast<int>(u(*rng) * (camera.width - 1))) =
        static_cast<uint8_t>(HoleCode::kNoReturn);
  f.depth.setTo(0.f, f.hole_mask != 0);
  return f;
}

// Every relative pose a handheld capture can produce (forward, backward, vertical, diagonal,
// sideways, large rotations, views that barely overlap) on images from 640x480 down to 48x36,
// with and without lens distortion: every pair returns a status and nothing escapes.
TEST(FillHolesByStereo, SurvivesRandomPairGeometries) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const std::set<std::string> paths = {"rectified_sgbm", "plane_sweep_forward",
                                       "plane_sweep_degenerate_rectification",
                                       "plane_sweep_requested", "none"};
  const cv::Size sizes[] = {{640, 480}, {320, 240}, {160, 120}, {96, 128}, {64, 48}, {24, 18}};
  std::map<std::string, int> seen;
  for (int trial = 0; trial < 72; ++trial) {
    const cv::Size size = sizes[trial < 6 ? trial : 1 + trial % 5];
    Camera camera;
    camera.width = size.width;
    camera.height = size.height;
    camera.fx = camera.fy = 0.8 * size.width;
    camera.cx = 0.5 * (size.width - 1);
    camera.cy = 0.5 * (size.height - 1);
    if (trial % 3 == 0) camera.distortion = testing::TumFr1Camera().distortion;
    // Directions by kind: forward, vertical, diagonal, sideways, random.
    const Eigen::Vector3d kinds[] = {{0.05 * u(rng), 0.05 * u(rng), 1},
                                     {0.2 * u(rng), 1, 0.3 * u(rng)},
                                     {1, 1, u(rng)},
                                     {1, 0.2 * u(rng), 0.2 * u(rng)},
                                     {u(rng), u(rng), u(rng)}};
    const Eigen::Vector3d direction = kinds[trial % 5].normalized() * (u(rng) < 0 ? -1 : 1);
    const double baseline = 0.02 + 0.25 * (u(rng) + 1);
    double degrees = trial % 7 == 0 ? 90 * u(rng) : 15 * u(rng);
    Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    if (trial % 6 == 5) {  // turned away sideways: the views barely overlap
      degrees = 90 + 20 * u(rng);
      axis = Eigen::Vector3d::UnitY();
    }
    const SE3 key1_from_key2(Eigen::AngleAxisd(degrees * M_PI / 180, axis).toRotationMatrix(),
                             baseline * direction);
    const RgbdFrame key1 = RandomFrame(camera, &rng), key2 = RandomFrame(camera, &rng),
                    key3 = RandomFrame(camera, &rng);
    const ThirdView third{&key3, key1_from_key2 * key1_from_key2};
    SCOPED_TRACE("trial " + std::to_string(trial) + ": " + std::to_string(size.width) + "x" +
                 std::to_string(size.height) + ", baseline " + std::to_string(baseline) +
                 " m, rotation " + std::to_string(degrees) + " deg");
    StereoFillResult r;
    ASSERT_NO_THROW(r = FillHolesByStereo(key1, key2, camera, key1_from_key2, {}, third));
    EXPECT_FALSE(r.termination.empty());
    const std::string path = PairPathName(r.path);
    EXPECT_EQ(paths.count(path), 1u) << path;
    ++seen[path];
    if (r.path == PairPath::kNone) ++seen["none: " + r.termination];
    // Measured pixels are never changed, whatever the geometry.
    EXPECT_EQ(cv::norm(r.filled_depth, key1.depth, cv::NORM_INF, key1.hole_mask == 0), 0.0);
  }
  for (const auto& [path, count] : seen) std::printf("%s: %d pairs\n", path.c_str(), count);
  // The geometries reach every path that a default run can take.
  EXPECT_GT(seen["rectified_sgbm"], 0);
  EXPECT_GT(seen["plane_sweep_forward"], 0);
  EXPECT_GT(seen["plane_sweep_degenerate_rectification"], 0);
}

}  // namespace
}  // namespace gf
