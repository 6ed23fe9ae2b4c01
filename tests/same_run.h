// Test helpers for reproducibility: a source that holds tracking back, and whether two runs of the
// same capture wrote the same outputs, value for value (the bytes a run folder would hold), apart
// from timings. Header-only, tests only.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/frame_source.h"
#include "pipeline/run_sink.h"

namespace gf::testing {

// A source whose frames take `delay` to read: tracking falls behind the other stages.
class PacedSource : public InMemoryFrameSource {
 public:
  PacedSource(CameraFile camera, std::vector<RgbdFrame> frames, std::chrono::milliseconds delay)
      : InMemoryFrameSource(std::move(camera), std::move(frames)), delay_(delay) {}
  bool Next(RgbdFrame* frame) override {
    std::this_thread::sleep_for(delay_);
    return InMemoryFrameSource::Next(frame);
  }

 private:
  std::chrono::milliseconds delay_;
};

// report.json without what measures time (the keys "seconds", "fps", "ms", "stages", any key
// ending in "_ms", and the machine's core count).
inline nlohmann::ordered_json WithoutTimings(const nlohmann::ordered_json& j) {
  if (j.is_array()) {
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    for (const auto& v : j) out.push_back(WithoutTimings(v));
    return out;
  }
  if (!j.is_object()) return j;
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const auto& [key, value] : j.items()) {
    const bool timing = key == "seconds" || key == "fps" || key == "ms" || key == "stages" ||
                        key == "hardware_concurrency" ||
                        (key.size() > 3 && key.compare(key.size() - 3, 3, "_ms") == 0);
    if (!timing) out[key] = WithoutTimings(value);
  }
  return out;
}

// Whether two images are the same bytes (type, size, every pixel).
inline bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  if (a.type() != b.type() || a.size() != b.size()) return false;
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0) return false;
  return true;
}

// Every output of run b equals run a's: trajectory, map (every surfel's every field), every
// keyframe's images, and the report apart from timings.
inline void ExpectSameRun(const InMemoryRunSink& a, const InMemoryRunSink& b) {
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (size_t i = 0; i < a.trajectory.size(); ++i) {
    EXPECT_EQ(a.trajectory[i].timestamp_text, b.trajectory[i].timestamp_text);
    EXPECT_TRUE(a.trajectory[i].world_from_camera.Matrix() ==
                b.trajectory[i].world_from_camera.Matrix())
        << "pose " << i;
  }
  EXPECT_EQ(a.map_written, b.map_written);
  ASSERT_EQ(a.map.size(), b.map.size());
  size_t different = 0;
  for (size_t i = 0; i < a.map.size(); ++i) {
    const Surfel &s = a.map[i], &t = b.map[i];
    different += s.position != t.position || s.normal != t.normal || s.radius != t.radius ||
                 s.confidence != t.confidence || s.red != t.red || s.green != t.green ||
                 s.blue != t.blue || s.source != t.source || s.keyframe != t.keyframe;
  }
  EXPECT_EQ(different, 0u) << "of " << a.map.size() << " surfels";
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (const auto& [name, k] : a.keyframes) {
    ASSERT_TRUE(b.keyframes.count(name)) << name;
    const InMemoryRunSink::Keyframe& l = b.keyframes.at(name);
    EXPECT_TRUE(SameImage(k.fill.filled_depth, l.fill.filled_depth)) << name;
    EXPECT_TRUE(SameImage(k.fill.fill_mask, l.fill.fill_mask)) << name;
    EXPECT_TRUE(SameImage(k.fill.confidence, l.fill.confidence)) << name;
    EXPECT_TRUE(SameImage(k.model_fill, l.model_fill)) << name;
    EXPECT_TRUE(SameImage(k.frame.hole_mask, l.frame.hole_mask)) << name;
  }
  EXPECT_EQ(WithoutTimings(a.report).dump(1), WithoutTimings(b.report).dump(1));
}

}  // namespace gf::testing
