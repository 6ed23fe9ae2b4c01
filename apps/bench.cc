#include "apps/bench.h"

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <thread>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/trajectory_metrics.h"
#include "apps/progress.h"
#include "registration/tracker.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

struct MethodResult {
  std::string name;
  Trajectory trajectory;
  std::vector<double> ms;
  int failures = 0;
};

nlohmann::ordered_json Summarise(const MethodResult& m, const Trajectory* gt) {
  std::vector<double> sorted = m.ms;
  std::sort(sorted.begin(), sorted.end());
  double total = 0;
  for (double v : m.ms) total += v;
  nlohmann::ordered_json j;
  j["method"] = m.name;
  j["frames"] = m.trajectory.size();
  j["median_ms"] = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
  j["fps"] = total > 0 ? 1000.0 * m.ms.size() / total : 0.0;
  j["failed_frames"] = m.failures;
  if (gt) {
    const TrajectoryErrorSummary s = EvaluateTrajectory(*gt, m.trajectory);
    j["ate_rmse_m"] = s.success ? nlohmann::json(s.ate_rmse_m) : nlohmann::json(nullptr);
    j["rpe_trans_rmse_m"] =
        s.success ? nlohmann::json(s.rpe_trans_rmse_m) : nlohmann::json(nullptr);
  }
  return j;
}

Eigen::Matrix4d ToEigen(const cv::Mat& m) {
  Eigen::Matrix4d e;
  cv::cv2eigen(m, e);
  return e;
}

}  // namespace

bool BenchOptions::Check(std::string* message) const {
  if (input.empty() || first_frame < 0 || (end_frame >= 0 && end_frame <= first_frame)) {
    if (message) *message = "need INPUT and 0 <= A < B in --frames A:B";
    return false;
  }
  return source.Check(message);
}

nlohmann::ordered_json RunBench(const BenchOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(options.input, "bad options: " + problem);
  FrameSourceOptions source_options = options.source;
  source_options.load_color = true;  // our SURF features and RgbdOdometry need intensity
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.input, source_options);
  const Camera camera = source->camera();

  std::vector<RgbdFrame> frames;
  {
    TerminalProgress progress("bench: loading", source->FrameCount());
    RgbdFrame f;
    for (int index = 0; (options.end_frame < 0 || index < options.end_frame) && source->Next(&f);
         ++index) {
      if (index >= options.first_frame) frames.push_back(f);
      progress.Update(index + 1);
    }
  }
  if (frames.size() < 2) throw InputError(options.input, "bench needs at least 2 frames");

  std::string gt_path = options.gt;
  for (const char* name : {"groundtruth.txt", "groundtruth.log"})
    if (gt_path.empty() && IsRegularFile((fs::path(options.input) / name).string()))
      gt_path = (fs::path(options.input) / name).string();
  Trajectory gt;
  if (!gt_path.empty()) gt = ReadTrajectory(gt_path);

  std::vector<MethodResult> results;
  {
    MethodResult ours{"glassfusion frame-to-keyframe ICP", {}, {}, 0};
    FrameToKeyframeTracker tracker(camera, TrackerOptions{});
    TerminalProgress progress("bench: glassfusion", static_cast<int>(frames.size()));
    for (const RgbdFrame& f : frames) {
      const auto t0 = Clock::now();
      const TrackingResult r = tracker.Track(f);
      ours.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      ours.failures += r.status == TrackingStatus::kLost;
      ours.trajectory.push_back({f.timestamp, f.timestamp_text, r.world_from_camera});
      progress.Update(static_cast<int>(ours.ms.size()));
    }
    results.push_back(std::move(ours));
  }

  if (options.peers) {
    cv::Mat k;
    camera.CvK().convertTo(k, CV_32F);
    std::vector<std::pair<std::string, cv::Ptr<cv::rgbd::Odometry>>> peers = {
        {"opencv RgbdOdometry", cv::rgbd::RgbdOdometry::create(k)},
        {"opencv ICPOdometry", cv::rgbd::ICPOdometry::create(k)},
        {"opencv RgbdICPOdometry", cv::rgbd::RgbdICPOdometry::create(k)},
        {"opencv FastICPOdometry", cv::rgbd::FastICPOdometry::create(k)},
    };
    std::vector<cv::Mat> gray(frames.size()), masks(frames.size());
    for (size_t i = 0; i < frames.size(); ++i) {
      cv::cvtColor(frames[i].color, gray[i], cv::COLOR_BGR2GRAY);
      masks[i] = frames[i].depth > 0;
    }
    for (auto& [name, odometry] : peers) {
      MethodResult m{name, {}, {}, 0};
      TerminalProgress progress("bench: " + name, static_cast<int>(frames.size()));
      SE3 world_from_current;
      m.trajectory.push_back({frames[0].timestamp, frames[0].timestamp_text, world_from_current});
      for (size_t i = 1; i < frames.size(); ++i) {
        cv::Mat rt;
        const auto t0 = Clock::now();
        bool ok = false;
        try {
          ok = odometry->compute(gray[i - 1], frames[i - 1].depth, masks[i - 1], gray[i],
                                 frames[i].depth, masks[i], rt);
        } catch (const cv::Exception&) {
          ok = false;
        }
        m.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        if (ok && !rt.empty()) {
          world_from_current = world_from_current * SE3::FromMatrix(ToEigen(rt)).Inverse();
        } else {
          ++m.failures;
        }
        m.trajectory.push_back({frames[i].timestamp, frames[i].timestamp_text, world_from_current});
        progress.Update(static_cast<int>(i + 1));
      }
      results.push_back(std::move(m));
    }
  }

  nlohmann::ordered_json out;
  out["input"] = options.input;
  out["frames"] = frames.size();
  out["cores"] = std::thread::hardware_concurrency();
  out["ground_truth"] = gt_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(gt_path);
  out["methods"] = nlohmann::json::array();
  for (const MethodResult& m : results)
    out["methods"].push_back(Summarise(m, gt.empty() ? nullptr : &gt));
  return out;
}

}  // namespace gf
