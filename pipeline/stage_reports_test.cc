#include "pipeline/stage_reports.h"

#include <gtest/gtest.h>

namespace gf {
namespace {

using json = nlohmann::ordered_json;

KeyframeFill Keyframe(const std::string& name, int holes, int filled, double ms,
                      const std::string& partner) {
  KeyframeFill k;
  k.timestamp = name;
  k.partner = partner;
  k.path = partner.empty() ? "" : "rectified_sgbm";
  k.hole_pixels = holes;
  k.filled_pixels = filled;
  k.stereo_error_median_m = 0.01 * filled / holes;
  k.ms = ms;
  return k;
}

TEST(StepTimes, MedianMaxAndCountOrNullTimes) {
  const StepTimes t = StepTimes::Of({30, 10, 20, 40});
  EXPECT_EQ(*t.median_ms, 30);  // the upper median
  EXPECT_EQ(*t.max_ms, 40);
  EXPECT_EQ(t.count, 4u);
  EXPECT_EQ(json(t).dump(), R"({"median_ms":30.0,"max_ms":40.0,"count":4})");
  EXPECT_EQ(json(StepTimes::Of({})).dump(), R"({"median_ms":null,"max_ms":null,"count":0})");
}

// The fill's totals are the sums of its keyframes' records; paired keyframes alone have times
// and errors; a failed keyframe is listed with its reason.
TEST(FillReport, TotalsFollowTheKeyframes) {
  std::vector<KeyframeFill> keyframes = {Keyframe("1.0", 100, 50, 20, "2.0"),
                                         Keyframe("2.0", 200, 150, 40, "1.0"),
                                         Keyframe("3.0", 100, 0, 0, "")};
  keyframes[2].failure = "no features";
  const FillReport r = FillReport::Of(keyframes, 1, 2);
  EXPECT_EQ(r.hole_pixels, 400);
  EXPECT_EQ(r.filled_pixels, 200);
  EXPECT_DOUBLE_EQ(r.fill_rate(), 0.5);
  EXPECT_EQ(r.keyframes_filled, 3);
  EXPECT_EQ(r.keyframes_paired, 2);
  EXPECT_EQ(r.keyframes_dropped, 1);
  EXPECT_EQ(r.keyframes_not_filled, 2);
  EXPECT_EQ(*r.pair_max_ms, 40);
  EXPECT_NEAR(*r.stereo_error_median_m, 0.0075, 1e-12);  // upper median of 0.005 and 0.0075
  ASSERT_EQ(r.failed_keyframes.size(), 1u);
  EXPECT_EQ(r.failed_keyframes[0].timestamp, "3.0");
  const json j = r;
  EXPECT_EQ(j["pair_paths"]["rectified_sgbm"], 2);
  EXPECT_EQ(j["per_keyframe"].size(), 3u);
  EXPECT_EQ(j["per_keyframe"][2]["partner"], nullptr);
  EXPECT_FALSE(j.contains("model_completion"));  // until the map has completed the keyframes
}

TEST(FillReport, WithoutKeyframesHasNoTimesNorErrors) {
  const json j = FillReport::Of({}, 0, 0);
  EXPECT_EQ(j["fill_rate"], 0.0);
  EXPECT_TRUE(j["stereo_error_median_m"].is_null());
  EXPECT_TRUE(j["pair_median_ms"].is_null());
  EXPECT_TRUE(j["failed_keyframes"].is_array());
}

// A run without loop closure says so and nothing else; a surfel report counts the failed items.
TEST(StageReports, DisabledLoopsAndFusionFailures) {
  EXPECT_EQ(json(LoopReport()).dump(), R"({"enabled":false})");
  LoopReport loops;
  loops.enabled = true;
  loops.loops.push_back({"5.0", "1.0", true});
  const json l = loops;
  EXPECT_EQ(l["loops"][0]["with"], "1.0");
  EXPECT_EQ(l["relocalisation"]["found"], 0);
  SurfelReport s;
  s.failed_frames = 2;
  s.failed_fills = 1;
  const json j = s;
  EXPECT_EQ(j["failed_items"], 3);
  EXPECT_TRUE(j["first_failure"].is_null());
}

}  // namespace
}  // namespace gf
