#include "sfm/keyframe_pairs.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "sfm/stereo_fill.h"

namespace gf {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

Eigen::Vector3d NormalizedRay(const Camera& camera, const cv::Point2f& pixel) {
  return camera.UndistortPixel({pixel.x, pixel.y}).homogeneous();
}

// key1_from_key2 by OpenCV's dense photometric RGB-D odometry, started from `initial`. The images
// and depth are undistorted first (the odometry assumes a pinhole camera).
bool PhotometricRefine(const RgbdFrame& key1, const RgbdFrame& key2, const Camera& camera,
                       const SE3& initial, SE3* refined) {
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
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry = cv::rgbd::RgbdOdometry::create(
      k, 0.3f, 5.f, 0.07f, std::vector<int>{10, 10, 10, 10}, std::vector<float>(), 0.5f);
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

// Dense photometric alignment from a successful feature refinement (OpenCV's RgbdOdometry on
// undistorted images): the stereo needs the pose under which key1's colour and key2's colour agree.
// The change is reported against `initial` (the tracked pose).
void AddPhotometricStep(const StereoKeyframe& key1, const StereoKeyframe& key2,
                        const Camera& camera, const SE3& initial,
                        const PoseRefinementOptions& options, PoseRefinement* r) {
  if (!r->success) return;
  SE3 photometric;
  if (!PhotometricRefine(key1.frame, key2.frame, camera, r->key1_from_key2, &photometric)) return;
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

}  // namespace

bool PairSelectionOptions::Check(std::string* message) const {
  auto fail = [&](const char* m) {
    if (message) *message = m;
    return false;
  };
  if (min_matches < 1) return fail("min_matches must be positive");
  if (max_evaluations < 1) return fail("max_evaluations must be positive");
  if (!(min_baseline_m > 0) || !(max_baseline_m > min_baseline_m))
    return fail("need 0 < min_baseline_m < max_baseline_m");
  if (!(max_rotation_deg > 0)) return fail("max_rotation_deg must be positive");
  if (!(min_median_disparity_px >= 0) || !(max_near_disparity_px > min_median_disparity_px) ||
      !(max_near_disparity_sweep_px > min_median_disparity_px) || !(epipole_margin_px >= 0))
    return fail("need 0 <= min_median_disparity_px < max_near_disparity_px, margin >= 0");
  if (window < 1 || lookahead < 0) return fail("need window >= 1 and lookahead >= 0");
  return surf.Check(message) && match.Check(message) && refine.Check(message);
}

bool PoseRefinementOptions::Check(std::string* message) const {
  if (!(reprojection_px > 0) || min_inliers < 6 || !(max_change_m > 0) || !(max_change_deg > 0)) {
    if (message) *message = "pose refinement: positive thresholds, min_inliers >= 6";
    return false;
  }
  return true;
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

std::string PairChoice::BriefReport() const {
  char buffer[200];
  if (!found) {
    std::snprintf(buffer, sizeof(buffer), "no stereo partner: %s (%d candidates matched)",
                  reason.c_str(), evaluated);
  } else {
    std::snprintf(buffer, sizeof(buffer),
                  "partner %d: baseline %.3f m, rotation %.1f deg, %d RANSAC inlier matches%s",
                  partner, baseline_m, rotation_deg, matches, third >= 0 ? ", third view" : "");
  }
  return buffer;
}

PairChoice SelectPartner(const StereoKeyframe& key1,
                         const std::vector<std::shared_ptr<const StereoKeyframe>>& candidates,
                         const Camera& camera, const PairSelectionOptions& options) {
  PairChoice choice;
  struct Geometry {
    int index;
    double baseline, rotation_deg;
    bool forward;
  };
  // Key1's depth range (median and 5th percentile of its measured depth).
  const std::vector<float> depths = SortedDepthSample(key1.frame.depth, 4);
  if (depths.size() < 100) {
    choice.reason = "keyframe has almost no measured depth";
    return choice;
  }
  const double median_depth = depths[depths.size() / 2], near_depth = depths[depths.size() / 20];
  const double f = 0.5 * (camera.fx + camera.fy);
  std::vector<Geometry> in_range;
  int too_short = 0, too_long = 0, too_rotated = 0, forward = 0;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const SE3 rel = key1.world_from_camera.Inverse() * candidates[i]->world_from_camera;
    const bool is_forward = IsForwardPair(camera, rel, options.epipole_margin_px);
    const Geometry g{static_cast<int>(i), rel.TranslationNorm(), rel.RotationAngle() * kDegPerRad,
                     is_forward};
    // Parallax comes from the motion across key1's optical axis, or from all of it when forward
    // pairs go to the plane sweep.
    const double lateral = options.allow_forward ? g.baseline : rel.translation().head<2>().norm();
    // Rectified stereo searches a fixed disparity range; the plane sweep (forward pairs) does not.
    const double max_near_disparity =
        is_forward ? options.max_near_disparity_sweep_px : options.max_near_disparity_px;
    if (g.baseline < options.min_baseline_m ||
        f * lateral / median_depth < options.min_median_disparity_px) {
      ++too_short;
    } else if (g.baseline > options.max_baseline_m ||
               f * lateral / near_depth > max_near_disparity) {
      ++too_long;
    } else if (g.rotation_deg > options.max_rotation_deg) {
      ++too_rotated;
    } else if (!options.allow_forward && is_forward) {
      ++forward;
    } else {
      in_range.push_back(g);
    }
  }
  // Farthest first: the first candidate with enough matches is the partner, the next the third
  // (for a forward partner with spread_third_view_forward: the rest are re-ordered farthest from
  // the partner first).
  std::sort(in_range.begin(), in_range.end(),
            [](const Geometry& a, const Geometry& b) { return a.baseline > b.baseline; });
  // The tracked relative pose can be a few centimetres off; each candidate's pose is refined
  // (PnP on the matches) and its RANSAC inliers count as the pair's matches.
  int fewest_short = 0;
  const SE3 key1_from_world = key1.world_from_camera.Inverse();
  PoseRefinementOptions features_only = options.refine;
  features_only.photometric = false;  // dense alignment only for the chosen views, below
  for (size_t n = 0; n < in_range.size(); ++n) {
    if (choice.evaluated >= options.max_evaluations) break;
    const Geometry g = in_range[n];
    const PoseRefinement pose = RefinePairPose(
        key1, *candidates[g.index], camera,
        key1_from_world * candidates[g.index]->world_from_camera, options.match, features_only);
    ++choice.evaluated;
    if (!pose.success || pose.inliers < options.min_matches) {
      fewest_short = std::max(fewest_short, pose.inliers);
      continue;
    }
    if (choice.found) {
      choice.third = g.index;
      choice.third_pose = pose;
      break;
    }
    choice.found = true;
    choice.partner = g.index;
    choice.matches = pose.inliers;
    choice.baseline_m = pose.key1_from_key2.TranslationNorm();
    choice.rotation_deg = pose.key1_from_key2.RotationAngle() * kDegPerRad;
    choice.partner_pose = pose;
    if (g.forward && options.spread_third_view_forward) {
      const Eigen::Vector3d partner_at = candidates[g.index]->world_from_camera.translation();
      const auto from_partner = [&](const Geometry& c) {
        return (candidates[c.index]->world_from_camera.translation() - partner_at).norm();
      };
      std::sort(
          in_range.begin() + n + 1, in_range.end(),
          [&](const Geometry& a, const Geometry& b) { return from_partner(a) > from_partner(b); });
    }
  }
  if (options.refine.photometric) {
    if (choice.found)
      AddPhotometricStep(key1, *candidates[choice.partner], camera,
                         key1_from_world * candidates[choice.partner]->world_from_camera,
                         options.refine, &choice.partner_pose);
    if (choice.third >= 0)
      AddPhotometricStep(key1, *candidates[choice.third], camera,
                         key1_from_world * candidates[choice.third]->world_from_camera,
                         options.refine, &choice.third_pose);
  }
  if (!choice.found) {
    char buffer[200];
    if (in_range.empty()) {
      std::snprintf(buffer, sizeof(buffer),
                    "no keyframe with usable parallax (%d too close, %d too far, %d rotated too "
                    "much, %d forward motion)",
                    too_short, too_long, too_rotated, forward);
    } else {
      std::snprintf(buffer, sizeof(buffer),
                    "too few matches (best %d RANSAC inliers of %d needed, %d candidates)",
                    fewest_short, options.min_matches, choice.evaluated);
    }
    choice.reason = buffer;
  }
  return choice;
}

KeyframePairScheduler::KeyframePairScheduler(const Camera& camera,
                                             const PairSelectionOptions& options)
    : camera_(camera), options_(options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
}

StereoJob KeyframePairScheduler::MakeJob(size_t position) const {
  StereoJob job;
  job.key1 = keyframes_[position];
  std::vector<std::shared_ptr<const StereoKeyframe>> candidates;
  for (size_t i = 0; i < keyframes_.size(); ++i)
    if (i != position) candidates.push_back(keyframes_[i]);
  try {
    job.choice = SelectPartner(*job.key1, candidates, camera_, options_);
  } catch (const std::exception& e) {
    // One keyframe's failure must not stall the stream: the job goes out without a partner.
    job.error = std::string("pair selection failed: ") + e.what();
    job.choice = PairChoice();
    job.choice.reason = job.error;
    return job;
  }
  if (job.choice.found) job.key2 = candidates[job.choice.partner];
  if (job.choice.third >= 0) job.third = candidates[job.choice.third];
  return job;
}

std::vector<StereoJob> KeyframePairScheduler::Add(const RgbdFrame& frame,
                                                  const SE3& world_from_camera) {
  keyframes_.push_back(
      MakeStereoKeyframe(next_id_++, frame, world_from_camera, camera_, options_.surf));
  ++pending_;
  std::vector<StereoJob> jobs;
  if (pending_ > static_cast<size_t>(options_.lookahead)) {
    // The oldest pending keyframe now has `lookahead` later ones.
    jobs.push_back(MakeJob(keyframes_.size() - pending_));
    --pending_;
  }
  // Keep `window` paired keyframes before the pending ones.
  while (keyframes_.size() > pending_ + static_cast<size_t>(options_.window))
    keyframes_.pop_front();
  return jobs;
}

std::vector<StereoJob> KeyframePairScheduler::Flush() {
  std::vector<StereoJob> jobs;
  for (; pending_ > 0; --pending_) jobs.push_back(MakeJob(keyframes_.size() - pending_));
  return jobs;
}

}  // namespace gf
