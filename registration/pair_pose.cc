#include "registration/pair_pose.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

Eigen::Vector3d NormalizedRay(const Camera& camera, const cv::Point2f& pixel) {
  return camera.UndistortPixel({pixel.x, pixel.y}).homogeneous();
}

// key1_from_key2 by OpenCV's dense photometric RGB-D odometry, started from `initial`. The images
// and depth are undistorted first (the odometry assumes a pinhole camera).
bool PhotometricRefine(const RgbdFrame& key1, const RgbdFrame& key2, const Camera& camera,
                       const std::vector<int>& iterations, const SE3& initial, SE3* refined) {
  cv::Mat map_x, map_y;
  camera.UndistortionMaps(&map_x, &map_y);
  auto prepare = [&](const RgbdFrame& f, cv::Mat* gray, cv::Mat* depth) {
    cv::Mat g;
    cv::cvtColor(f.color, g, cv::COLOR_BGR2GRAY);
    cv::remap(g, *gray, map_x, map_y, cv::INTER_LINEAR);
    cv::remap(f.depth, *depth, map_x, map_y, cv::INTER_NEAREST);
  };
  cv::Mat gray1, depth1, gray2, depth2, k;
  prepare(key1, &gray1, &depth1);
  prepare(key2, &gray2, &depth2);
  camera.CvK().convertTo(k, CV_32F);
  // Depth 0.3-5 m, matched points at most 7 cm apart in depth, at most half the image's pixels (the
  // most textured).
  // OpenCV replaces the iteration counts by its defaults unless gradient magnitudes come with
  // them (one per level; 10 is OpenCV's default).
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry = cv::rgbd::RgbdOdometry::create(
      k, 0.3f, 5.f, 0.07f, iterations, std::vector<float>(iterations.size(), 10.f), 0.5f);
  cv::Mat init, rt;
  cv::eigen2cv(initial.Matrix(), init);
  // compute() returns dst_from_src for (src = key2, dst = key1).
  if (!odometry->compute(gray2, depth2, cv::Mat(), gray1, depth1, cv::Mat(), rt, init))
    return false;
  Eigen::Matrix4d out;
  cv::cv2eigen(rt, out);
  *refined = SE3::FromMatrix(out);
  return true;
}

}  // namespace

void AddPhotometricStep(const StereoKeyframe& key1, const StereoKeyframe& key2,
                        const Camera& camera, const SE3& initial,
                        const PoseRefinementOptions& options, PoseRefinement* r) {
  if (!r->success) return;
  SE3 photometric;
  if (!PhotometricRefine(key1.frame, key2.frame, camera, options.photometric_iterations,
                         r->key1_from_key2, &photometric)) return;
  const SE3 step = r->key1_from_key2.Inverse() * photometric;
  if (step.TranslationNorm() > options.max_change_m ||
      step.RotationAngle() * kDegPerRad > options.max_change_deg)
    return;
  r->key1_from_key2 = photometric;
  r->termination = "refined (features + photometric)";
  const SE3 total = initial.Inverse() * photometric;
  r->change_m = total.TranslationNorm();
  r->change_deg = total.RotationAngle() * kDegPerRad;
}

bool PoseRefinementOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("reprojection_px", reprojection_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("min_inliers", min_inliers, 6, kMaxImagePixels, kMoreThanAnImagesPixels)
      .Above("max_change_m", max_change_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("max_change_deg", max_change_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .Require(photometric_iterations.size() <= 6,
               "photometric_iterations: at most 6 pyramid levels")
      .Each("photometric_iterations", photometric_iterations, 0, kMaxIterations,
            kMoreIterationsThanAFrameAllows);
  return c.ok();
}

std::string PoseRefinement::BriefReport() const {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer),
                "pair pose %s: %d of %d matches inliers, rmse %.2f px, moved %.1f mm / %.2f deg",
                termination.c_str(), inliers, matches, rmse_px, 1000 * change_m, change_deg);
  return buffer;
}

PoseRefinement RefinePairPose(const StereoKeyframe& key1, const StereoKeyframe& key2,
                              const Camera& camera, const SE3& initial_key1_from_key2,
                              const MatchOptions& match, const PoseRefinementOptions& options) {
  PoseRefinement r;
  r.key1_from_key2 = initial_key1_from_key2;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  if (!key1.keypoints.empty() && !key2.keypoints.empty()) {
    for (const cv::DMatch& m : MatchDescriptors(key2.keypoints, key2.descriptors, key1.keypoints,
                                                key1.descriptors, match)) {
      const Eigen::Vector3d& p = key2.points[m.queryIdx];
      if (std::isnan(p.z())) continue;
      object.emplace_back(p.x(), p.y(), p.z());
      image.push_back(key1.keypoints[m.trainIdx].pt);
    }
  }
  r.matches = static_cast<int>(object.size());
  if (r.matches < options.min_inliers) {
    r.termination = "too few matches with depth";
    return r;
  }
  // Rodrigues vector and translation of key1_from_key2 as the starting point.
  const Eigen::Vector3d rv = SO3Log(initial_key1_from_key2.rotation());
  const Eigen::Vector3d t0 = initial_key1_from_key2.translation();
  cv::Mat rvec = (cv::Mat_<double>(3, 1) << rv.x(), rv.y(), rv.z());
  cv::Mat tvec = (cv::Mat_<double>(3, 1) << t0.x(), t0.y(), t0.z());
  std::vector<int> inliers;
  const bool ok = cv::solvePnPRansac(object, image, camera.CvK(), camera.CvDistortion(), rvec, tvec,
                                     true, 500, static_cast<float>(options.reprojection_px), 0.999,
                                     inliers, cv::SOLVEPNP_ITERATIVE);
  r.inliers = static_cast<int>(inliers.size());
  if (!ok || r.inliers < options.min_inliers) {
    r.termination = "too few inliers";
    return r;
  }
  std::vector<cv::Point3f> in_object;
  std::vector<cv::Point2f> in_image;
  for (int i : inliers) {
    in_object.push_back(object[i]);
    in_image.push_back(image[i]);
  }
  cv::solvePnPRefineLM(in_object, in_image, camera.CvK(), camera.CvDistortion(), rvec, tvec);
  std::vector<cv::Point2f> projected;
  cv::projectPoints(in_object, rvec, tvec, camera.CvK(), camera.CvDistortion(), projected);
  double sum = 0;
  for (size_t i = 0; i < projected.size(); ++i) {
    const cv::Point2f d = projected[i] - in_image[i];
    sum += d.dot(d);
  }
  r.rmse_px = std::sqrt(sum / std::max<size_t>(1, projected.size()));
  const SE3 refined(SO3Exp({rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)}),
                    Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  const SE3 change = initial_key1_from_key2.Inverse() * refined;
  r.change_m = change.TranslationNorm();
  r.change_deg = change.RotationAngle() * kDegPerRad;
  if (r.change_m > options.max_change_m || r.change_deg > options.max_change_deg) {
    r.termination = "implausibly far from the tracked pose";
    return r;
  }
  r.success = true;
  r.termination = "refined";
  r.key1_from_key2 = refined;
  if (options.photometric)
    AddPhotometricStep(key1, key2, camera, initial_key1_from_key2, options, &r);
  return r;
}

std::shared_ptr<const StereoKeyframe> MakeStereoKeyframe(int id, const RgbdFrame& frame,
                                                         const SE3& world_from_camera,
                                                         const Camera& camera,
                                                         const SurfOptions& surf) {
  GF_CHECK(frame.color.type() == CV_8UC3, "stereo keyframes need BGR colour");
  auto k = std::make_shared<StereoKeyframe>();
  k->id = id;
  k->frame = frame;
  k->world_from_camera = world_from_camera;
  cv::Mat gray;
  cv::cvtColor(frame.color, gray, cv::COLOR_BGR2GRAY);
  SurfFeatures f = DetectAndDescribeSurf(gray, surf);
  k->keypoints = std::move(f.keypoints);
  k->descriptors = f.descriptors;
  for (const cv::KeyPoint& kp : k->keypoints) {
    const int u = static_cast<int>(std::lround(kp.pt.x)),
              v = static_cast<int>(std::lround(kp.pt.y));
    const float z = (u >= 0 && v >= 0 && u < frame.depth.cols && v < frame.depth.rows)
                        ? frame.depth.at<float>(v, u)
                        : 0.f;
    k->points.push_back(z > 0 ? Eigen::Vector3d(NormalizedRay(camera, kp.pt) * z)
                              : Eigen::Vector3d::Constant(std::nan("")));
  }
  return k;
}
}  // namespace gf
