#include "apps/fill_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "acquisition/errors.h"
#include "acquisition/image_io.h"
#include "acquisition/stats.h"
#include "sfm/fill_carry.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

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
  if (pairs.max_near_disparity_px > stereo.num_disparities) {
    if (message) *message = "pairs.max_near_disparity_px exceeds the stereo search range";
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
                              : queue_.Push({frame, world_from_camera}))
    return true;
  ++dropped_;
  spdlog::debug("fill: keyframe {} dropped (stereo worker busy)", frame.timestamp_text);
  return false;
}

void FillStage::Finish() {
  queue_.Close();
  if (worker_.joinable()) worker_.join();
  if (error_) std::rethrow_exception(error_);
}

void FillStage::Run() {
  try {
    KeyframePairScheduler scheduler(camera_, options_.pairs);
    Offered item;
    while (queue_.Pop(&item)) {
      for (const StereoJob& job : scheduler.Add(item.frame, item.world_from_camera)) Process(job);
    }
    for (const StereoJob& job : scheduler.Flush()) Process(job);
  } catch (...) {
    error_ = std::current_exception();
    queue_.Close();  // later Offer() calls drop their frames
  }
}

void FillStage::Process(const StereoJob& job) {
  const auto start = std::chrono::steady_clock::now();
  const RgbdFrame& key1 = job.key1->frame;
  KeyframeFill k;
  k.timestamp = key1.timestamp_text;
  k.hole_pixels = cv::countNonZero(key1.hole_mask);
  StereoFillResult r;
  if (job.key2) {
    const SE3 key1_from_key2 = job.choice.partner_pose.key1_from_key2;
    ThirdView third;
    if (job.third) {
      third.frame = &job.third->frame;
      third.key1_from_key3 = job.choice.third_pose.key1_from_key2;
    }
    spdlog::debug("fill {}: {}; {}", k.timestamp, job.choice.BriefReport(),
                  job.choice.partner_pose.BriefReport());
    r = FillHolesByStereo(key1, job.key2->frame, camera_, key1_from_key2, options_.stereo, third);
    k.partner = job.key2->frame.timestamp_text;
    if (job.third) k.third = job.third->frame.timestamp_text;
    k.method = r.method;
    k.baseline_m = job.choice.baseline_m;
    k.matches = job.choice.matches;
    k.third_view = r.third_view_used;
    k.termination = r.termination;
    k.stereo_error_median_m = r.stereo_error_median_m;
    spdlog::debug("fill {}: {}", k.timestamp, r.BriefReport());
  } else {
    k.termination = job.choice.reason;
    spdlog::debug("fill {}: {}", k.timestamp, job.choice.BriefReport());
  }
  // The earlier keyframes' own fills, moved into this keyframe.
  const CarriedFillResult c = carrier_.Next(key1, job.key1->world_from_camera, &r);
  k.filled_pixels = c.filled_pixels;
  k.carried_pixels = c.carried_pixels;
  k.corrected_pixels = c.corrected_pixels;
  if (c.carried_pixels + c.corrected_pixels > 0)
    spdlog::debug("fill {}: {}", k.timestamp, c.BriefReport());
  k.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const fs::path base = fs::path(keyframe_dir_) / k.timestamp;
  WriteImage(base.string() + ".hole_mask.png", key1.hole_mask);
  WriteImage(base.string() + ".depth_filled.png", ToMillimetres(c.filled_depth));
  if (!key1.color.empty()) {
    WriteImage(base.string() + ".fill_overlay.png",
               Overlay(key1.color, c.filled_depth, c.fill_mask, c.confidence, c.source));
    WriteImage(base.string() + ".color.png", key1.color);  // for colmap-export
  }
  done_.push_back(k);
}

nlohmann::ordered_json FillStage::Report() const {
  long holes = 0, filled = 0, carried = 0, corrected = 0;
  int paired = 0;
  std::vector<double> errors, ms;
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const KeyframeFill& k : done_) {
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
      {"pair_median_ms",
       ms.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(ms[ms.size() / 2])},
      {"pair_max_ms", ms.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(ms.back())},
      {"per_keyframe", list}};
}

}  // namespace gf
