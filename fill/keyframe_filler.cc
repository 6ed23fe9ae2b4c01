#include "fill/keyframe_filler.h"

#include <chrono>
#include <opencv2/core.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// The jobs pair selection made ready, as tasks for the next steps.
std::vector<FillTask> Tasks(std::vector<StereoJob> jobs) {
  std::vector<FillTask> tasks(jobs.size());
  for (size_t i = 0; i < jobs.size(); ++i) tasks[i].job = std::move(jobs[i]);
  return tasks;
}

}  // namespace

bool KeyframeFillerOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Require(pairs.max_near_disparity_px <= stereo.sgbm.num_disparities,
            "pairs.max_near_disparity_px exceeds stereo.sgbm.num_disparities")
      // Pair selection picks a partner by the method that will fill it (its disparity limits
      // differ for forward pairs); the stereo must classify the pair the same way.
      .Require(pairs.geometry == stereo.geometry,
               "geometry: pair selection and stereo must share one geometry (the fill's "
               "`geometry`)")
      .Part("pairs", pairs)
      .Part("stereo", stereo)
      .Part("carry", carry);
  return c.ok();
}

KeyframeFiller::KeyframeFiller(const Camera& camera, const KeyframeFillerOptions& options)
    : camera_(camera),
      options_(options),
      scheduler_(camera, options.pairs),
      carrier_(camera, options.carry) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
}

std::vector<FillTask> KeyframeFiller::Pair(const RgbdFrame& frame,
                                           const SE3& world_from_camera) {
  const auto t0 = Clock::now();
  std::vector<StereoJob> jobs;
  try {
    jobs = scheduler_.Add(frame, world_from_camera);
  } catch (const std::exception& e) {
    // Its features could not be computed: it joins no pair, and keeps its sensor depth.
    auto key = std::make_shared<StereoKeyframe>();
    key->frame = frame;
    key->world_from_camera = world_from_camera;
    std::vector<FillTask> failed(1);
    failed[0].result = Failed(key, std::string("features: ") + e.what());
    failed[0].failed = true;
    return failed;
  }
  last_pairing_ms_ = Ms(t0, Clock::now());
  return Tasks(std::move(jobs));
}

std::vector<FillTask> KeyframeFiller::PairRest() {
  return Tasks(scheduler_.Flush());
}

std::vector<FilledKeyframe> KeyframeFiller::Add(const RgbdFrame& frame,
                                                const SE3& world_from_camera) {
  std::vector<FilledKeyframe> out;
  for (FillTask& task : Pair(frame, world_from_camera)) {
    Stereo(&task);
    out.push_back(Carry(std::move(task)));
  }
  return out;
}

std::vector<FilledKeyframe> KeyframeFiller::Flush(const std::function<bool()>& stop) {
  std::vector<FilledKeyframe> out;
  for (FillTask& task : PairRest()) {
    if (stop && stop()) break;
    Stereo(&task);
    out.push_back(Carry(std::move(task)));
  }
  return out;
}

void KeyframeFiller::Stereo(FillTask* task) const {
  if (task->failed) return;
  const StereoJob& job = task->job;
  const RgbdFrame& key1 = job.key1->frame;
  FilledKeyframe& out = task->result;
  out.key = job.key1;
  KeyframeFill& k = out.record;
  k.timestamp = KeyframeName(key1);
  k.hole_pixels = cv::countNonZero(key1.hole_mask);
  try {
    if (!job.error.empty()) throw std::runtime_error(job.error);
    const auto t0 = Clock::now();
    if (job.key2) {
      ThirdView third;
      if (job.third) third = {&job.third->frame, job.choice.third_pose.key1_from_key2};
      out.partner = job.key2;
      k.witnesses = static_cast<int>(job.witnesses.size());
      std::vector<ThirdView> witnesses;
      const SE3 key1_from_world = job.key1->world_from_camera.Inverse();
      for (const auto& w : job.witnesses)
        witnesses.push_back({&w->frame, key1_from_world * w->world_from_camera});
      out.stereo =
          FillHolesByStereo(key1, job.key2->frame, camera_, job.choice.partner_pose.key1_from_key2,
                            options_.stereo, third, witnesses);
      const StereoFillResult& r = out.stereo;
      k.partner = KeyframeName(job.key2->frame);
      if (job.third) k.third = KeyframeName(job.third->frame);
      k.method = FillMethodName(r.method);
      k.path = PairPathName(r.path);
      k.sgbm_refused = r.sgbm_refused;
      k.sgbm_rescaled = r.rectification.usable && r.rectification.rescaled;
      k.sgbm_vertical = r.rectification.usable && r.rectification.vertical;
      k.baseline_m = job.choice.baseline_m;
      k.matches = job.choice.matches;
      k.third_view = r.third_view_used;
      k.termination = r.termination;
      k.stereo_error_median_m = r.stereo_error_median_m;
      k.seen_through_pixels = r.rejected_by_free_space;
    } else {
      k.termination = job.choice.reason;
    }
    out.stereo_ms = Ms(t0, Clock::now());
  } catch (const std::exception& e) {
    task->result = Failed(job.key1, e.what());
    task->failed = true;
  }
}

FilledKeyframe KeyframeFiller::Carry(FillTask task) {
  if (task.failed) return std::move(task.result);
  FilledKeyframe out = std::move(task.result);
  try {
    const auto t0 = Clock::now();
    // The earlier keyframes' own fills, moved into this keyframe.
    out.fill = carrier_.Next(out.key->frame, out.key->world_from_camera,
                             out.partner ? &out.stereo : nullptr);
    out.carry_ms = Ms(t0, Clock::now());
  } catch (const std::exception& e) {
    return Failed(out.key, e.what());
  }
  KeyframeFill& k = out.record;
  k.filled_pixels = out.fill.filled_pixels;
  k.carried_pixels = out.fill.carried_pixels;
  k.corrected_pixels = out.fill.corrected_pixels;
  k.corroborated_pixels =
      out.fill.corroborated.empty() ? 0 : cv::countNonZero(out.fill.corroborated);
  k.ms = out.stereo_ms + out.carry_ms;
  return out;
}

FilledKeyframe KeyframeFiller::Failed(std::shared_ptr<const StereoKeyframe> key,
                                      const std::string& reason) {
  FilledKeyframe out;
  const RgbdFrame& frame = key->frame;
  out.key = std::move(key);
  out.record.timestamp = KeyframeName(frame);
  const bool well_formed = frame.depth.type() == CV_32FC1 && frame.hole_mask.type() == CV_8UC1 &&
                           frame.depth.size() == frame.hole_mask.size();
  out.record.hole_pixels = well_formed ? cv::countNonZero(frame.hole_mask) : 0;
  out.record.termination = "failed";
  out.record.failure = reason;
  CarriedFillResult& sensor_only = out.fill;
  sensor_only.filled_depth = frame.depth;
  sensor_only.fill_mask = cv::Mat::zeros(frame.depth.size(), CV_8UC1);
  sensor_only.source = cv::Mat::zeros(frame.depth.size(), CV_8UC1);
  sensor_only.confidence = cv::Mat::zeros(frame.depth.size(), CV_32FC1);
  sensor_only.corroborated = cv::Mat::zeros(frame.depth.size(), CV_8UC1);
  return out;
}

}  // namespace gf
