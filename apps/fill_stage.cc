#include "apps/fill_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "acquisition/errors.h"
#include "acquisition/image_io.h"
#include "acquisition/stats.h"
#include "sfm/fill_carry.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

// A keyframe's name in outputs: the depth timestamp as the input lists it, else the frame index.
std::string Name(const RgbdFrame& frame) {
  return frame.timestamp_text.empty() ? std::to_string(frame.index) : frame.timestamp_text;
}

cv::Mat ToMillimetres(const cv::Mat& depth_m) {
  cv::Mat mm(depth_m.size(), CV_16UC1);
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const double d = depth_m.at<float>(y, x) * 1000.0;
      mm.at<uint16_t>(y, x) = d > 0 ? static_cast<uint16_t>(std::min(65535.0, std::round(d))) : 0;
    }
  return mm;
}

// Filled pixels green, or cyan where carried from earlier keyframes (blend weight grows with
// confidence), holes still empty magenta.
cv::Mat Overlay(const cv::Mat& color, const cv::Mat& filled_depth, const cv::Mat& fill_mask,
                const cv::Mat& confidence, const cv::Mat& source) {
  cv::Mat out = color.clone();
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      cv::Vec3b& p = out.at<cv::Vec3b>(y, x);
      cv::Vec3d tint;
      double w;
      if (fill_mask.at<uint8_t>(y, x)) {
        tint = source.at<uint8_t>(y, x) == static_cast<uint8_t>(DepthSource::kCarried)
                   ? cv::Vec3d(255, 255, 0)
                   : cv::Vec3d(0, 255, 0);
        w = 0.35 + 0.4 * confidence.at<float>(y, x);
      } else if (!(filled_depth.at<float>(y, x) > 0)) {
        tint = {255, 0, 255};
        w = 0.35;
      } else {
        continue;
      }
      for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uint8_t>((1 - w) * p[c] + w * tint[c]);
    }
  return out;
}

}  // namespace

bool FillStageOptions::Check(std::string* message) const {
  if (queue_capacity < 1) {
    if (message) *message = "fill queue_capacity must be positive";
    return false;
  }
  if (pairs.max_near_disparity_px > stereo.sgbm.num_disparities) {
    if (message) *message = "pairs.max_near_disparity_px exceeds stereo.sgbm.num_disparities";
    return false;
  }
  if (pairs.epipole_margin_px != stereo.epipole_margin_px) {
    // Pair selection picks a partner by the method that will fill it (its disparity limits
    // differ for forward pairs); the stereo must classify the pair the same way.
    if (message) *message = "pairs.epipole_margin_px and stereo.epipole_margin_px must be equal";
    return false;
  }
  return pairs.Check(message) && stereo.Check(message) && carry.Check(message);
}

FillStage::FillStage(const Camera& camera, const FillStageOptions& options,
                     const std::string& out_dir)
    : camera_(camera),
      options_(options),
      keyframe_dir_((fs::path(out_dir) / "keyframes").string()),
      queue_(options.queue_capacity),
      carrier_(camera, options.carry) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  std::error_code ec;
  fs::create_directories(keyframe_dir_, ec);
  if (ec) throw InputError(keyframe_dir_, "cannot create folder: " + ec.message());
  worker_ = std::thread([this] { Run(); });
}

FillStage::~FillStage() {
  if (worker_.joinable()) {
    queue_.Close();
    worker_.join();
  }
}

bool FillStage::Offer(const RgbdFrame& frame, const SE3& world_from_camera) {
  if (options_.drop_when_busy ? queue_.TryPush({frame, world_from_camera})
                              : queue_.Push({frame, world_from_camera})) {
    ++accepted_;
    return true;
  }
  if (stopped_ || cancelled_) {
    ++not_filled_;
    spdlog::debug("fill: keyframe {} not filled (the fill stage has stopped)", Name(frame));
  } else {
    ++dropped_;
    spdlog::debug("fill: keyframe {} dropped (stereo worker busy: {} keyframes queued)",
                  Name(frame), options_.queue_capacity);
  }
  return false;
}

void FillStage::Finish(const std::function<bool()>& cancel) {
  queue_.Close();
  while (cancel && !stopped_ && !cancelled_) {
    if (cancel()) Cancel();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (worker_.joinable()) worker_.join();
  if (error_) std::rethrow_exception(error_);
}

void FillStage::Cancel() {
  cancelled_ = true;
  queue_.Close();
}

void FillStage::Run() {
  try {
    KeyframePairScheduler scheduler(camera_, options_.pairs);
    Offered item;
    while (!cancelled_ && queue_.Pop(&item)) {
      std::vector<StereoJob> jobs;
      try {
        jobs = scheduler.Add(item.frame, item.world_from_camera);
      } catch (const std::exception& e) {
        Skip(item.frame, std::string("features: ") + e.what());
        continue;
      }
      for (const StereoJob& job : jobs) Process(job);
    }
    if (!cancelled_)
      for (const StereoJob& job : scheduler.Flush())
        if (!cancelled_) Process(job);
  } catch (...) {
    error_ = std::current_exception();  // an output that could not be written
  }
  stopped_ = true;
  queue_.Close();  // later Offer() calls drop their frames
}

CarriedFillResult FillStage::Fill(const StereoJob& job, KeyframeFill* k) {
  const RgbdFrame& key1 = job.key1->frame;
  if (!job.error.empty()) throw std::runtime_error(job.error);
  StereoFillResult r;
  if (job.key2) {
    const SE3 key1_from_key2 = job.choice.partner_pose.key1_from_key2;
    ThirdView third;
    if (job.third) {
      third.frame = &job.third->frame;
      third.key1_from_key3 = job.choice.third_pose.key1_from_key2;
    }
    spdlog::debug("fill {}: {}; {}", k->timestamp, job.choice.BriefReport(),
                  job.choice.partner_pose.BriefReport());
    r = FillHolesByStereo(key1, job.key2->frame, camera_, key1_from_key2, options_.stereo, third);
    k->partner = Name(job.key2->frame);
    if (job.third) k->third = Name(job.third->frame);
    k->method = r.method;
    k->path = r.path;
    k->sgbm_refused = r.sgbm_refused;
    k->sgbm_rescaled = r.rectification.usable && r.rectification.rescaled;
    k->baseline_m = job.choice.baseline_m;
    k->matches = job.choice.matches;
    k->third_view = r.third_view_used;
    k->termination = r.termination;
    k->stereo_error_median_m = r.stereo_error_median_m;
    if (!r.rectification.r_left.empty())
      spdlog::debug("fill {}: {}", k->timestamp, r.rectification.BriefReport());
    spdlog::debug("fill {}: {}", k->timestamp, r.BriefReport());
  } else {
    k->termination = job.choice.reason;
    spdlog::debug("fill {}: {}", k->timestamp, job.choice.BriefReport());
  }
  // The earlier keyframes' own fills, moved into this keyframe.
  const CarriedFillResult c = carrier_.Next(key1, job.key1->world_from_camera, &r);
  if (c.carried_pixels + c.corrected_pixels > 0)
    spdlog::debug("fill {}: {}", k->timestamp, c.BriefReport());
  return c;
}

void FillStage::Process(const StereoJob& job) {
  const auto start = std::chrono::steady_clock::now();
  const RgbdFrame& key1 = job.key1->frame;
  KeyframeFill k;
  k.timestamp = Name(key1);
  k.hole_pixels = cv::countNonZero(key1.hole_mask);
  CarriedFillResult c;
  try {
    c = Fill(job, &k);
  } catch (const std::exception& e) {
    // Contained: this keyframe keeps its sensor depth, the stage goes on.
    Skip(key1, e.what());
    return;
  }
  k.filled_pixels = c.filled_pixels;
  k.carried_pixels = c.carried_pixels;
  k.corrected_pixels = c.corrected_pixels;
  k.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  Write(key1, c);
  done_.push_back(k);
}

void FillStage::Skip(const RgbdFrame& key1, const std::string& reason) {
  spdlog::warn("fill: keyframe {} skipped: {}", Name(key1), reason);
  KeyframeFill k;
  k.timestamp = Name(key1);
  k.hole_pixels = cv::countNonZero(key1.hole_mask);
  k.termination = "failed";
  k.failure = reason;
  CarriedFillResult sensor_only;
  sensor_only.filled_depth = key1.depth;
  sensor_only.fill_mask = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  sensor_only.source = cv::Mat::zeros(key1.depth.size(), CV_8UC1);
  sensor_only.confidence = cv::Mat::zeros(key1.depth.size(), CV_32FC1);
  Write(key1, sensor_only);
  done_.push_back(k);
}

void FillStage::Write(const RgbdFrame& key1, const CarriedFillResult& c) const {
  const fs::path base = fs::path(keyframe_dir_) / Name(key1);
  WriteImage(base.string() + ".hole_mask.png", key1.hole_mask);
  WriteImage(base.string() + ".depth_filled.png", ToMillimetres(c.filled_depth));
  if (key1.color.type() == CV_8UC3 && key1.color.size() == key1.depth.size()) {
    WriteImage(base.string() + ".fill_overlay.png",
               Overlay(key1.color, c.filled_depth, c.fill_mask, c.confidence, c.source));
    WriteImage(base.string() + ".color.png", key1.color);  // for colmap-export
  }
}

nlohmann::ordered_json FillStage::Report() const {
  long holes = 0, filled = 0, carried = 0, corrected = 0;
  int paired = 0;
  std::vector<double> errors, ms;
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  nlohmann::ordered_json failed = nlohmann::ordered_json::array();
  // How many pairs took which path, and why sideways pairs did not get SGBM.
  nlohmann::ordered_json paths = {{"rectified_sgbm", 0},
                                  {"plane_sweep_forward", 0},
                                  {"plane_sweep_degenerate_rectification", 0},
                                  {"plane_sweep_requested", 0},
                                  {"none", 0}};
  nlohmann::ordered_json refused = {{"valid_region", 0}, {"disparity_range", 0}};
  int rescaled = 0;  // SGBM pairs whose crop's focal length was reduced to fit the search
  for (const KeyframeFill& k : done_) {
    if (!k.failure.empty()) failed.push_back({{"timestamp", k.timestamp}, {"reason", k.failure}});
    if (!k.path.empty()) paths[k.path] = paths.value(k.path, 0) + 1;
    if (!k.sgbm_refused.empty()) refused[k.sgbm_refused] = refused.value(k.sgbm_refused, 0) + 1;
    rescaled += k.sgbm_rescaled;
    holes += k.hole_pixels;
    filled += k.filled_pixels;
    carried += k.carried_pixels;
    corrected += k.corrected_pixels;
    if (!k.partner.empty()) {
      ++paired;
      ms.push_back(k.ms);
      if (k.filled_pixels > 0) errors.push_back(k.stereo_error_median_m);
    }
    list.push_back(
        {{"timestamp", k.timestamp},
         {"partner",
          k.partner.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(k.partner)},
         {"baseline_m", k.baseline_m},
         {"matches", k.matches},
         {"third", k.third.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(k.third)},
         {"third_view", k.third_view},
         {"method", k.method},
         {"path", k.path.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(k.path)},
         {"hole_pixels", k.hole_pixels},
         {"filled_pixels", k.filled_pixels},
         {"carried_pixels", k.carried_pixels},
         {"corrected_pixels", k.corrected_pixels},
         {"fill_rate", k.hole_pixels ? double(k.filled_pixels) / k.hole_pixels : 0.0},
         {"stereo_error_median_m", k.stereo_error_median_m},
         {"ms", k.ms},
         {"termination", k.termination}});
  }
  std::sort(ms.begin(), ms.end());
  return {
      {"hole_pixels", holes},
      {"filled_pixels", filled},
      {"fill_rate", holes ? double(filled) / holes : 0.0},
      {"carried_pixels", carried},
      {"corrected_pixels", corrected},
      {"stereo_error_median_m",
       errors.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(Median(errors))},
      {"keyframes_filled", static_cast<int>(done_.size())},
      {"keyframes_paired", paired},
      {"keyframes_dropped", dropped_},
      // Queued but never filled (the run stopped first), and offered after the stage stopped.
      {"keyframes_not_filled", accepted_ - static_cast<int>(done_.size()) + not_filled_},
      {"failed_keyframes", failed},
      {"pair_paths", paths},
      {"sgbm_refused", refused},
      {"sgbm_rescaled", rescaled},
      {"pair_median_ms",
       ms.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(ms[ms.size() / 2])},
      {"pair_max_ms", ms.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(ms.back())},
      {"per_keyframe", list}};
}

}  // namespace gf
