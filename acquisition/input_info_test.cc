#include "acquisition/input_info.h"

#include <gtest/gtest.h>

#include "acquisition/errors.h"
#include "tests/testing.h"

namespace gf {
namespace {

TEST(Info, TumHeadSequence) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  int calls = 0;
  const auto j = InputInfo(tum, {}, [&](int done, int total) {
    ++calls;
    EXPECT_EQ(total, 144);
    EXPECT_EQ(done, calls);
  });
  EXPECT_EQ(j["source"], "tum");
  EXPECT_EQ(j["frames"], 144);  // depth frames with a colour frame within 20 ms
  EXPECT_EQ(j["depth_frames"], 150);
  EXPECT_EQ(j["unmatched_depth"], 6);
  EXPECT_EQ(j["width"], 640);
  EXPECT_EQ(j["height"], 480);
  EXPECT_EQ(j["intrinsics"]["fx"], 517.3);
  EXPECT_EQ(j["depth_convention"], "scaled_units(5000)");
  // About 25% of the head sequence's depth pixels are empty (datasets README); the Python check
  // on all 150 PNGs counts 25.10% zeros.
  EXPECT_NEAR(j["hole_fraction"].get<double>(), 0.2510, 0.0005);
  EXPECT_EQ(calls, 144);
}

TEST(Info, IclMicroAndNoisy) {
  GF_REQUIRE_DATASET(icl, "icl_livingroom1_micro");
  const auto j = InputInfo(icl, {});
  EXPECT_EQ(j["source"], "redwood");
  EXPECT_EQ(j["frames"], 211);
  EXPECT_EQ(j["depth_convention"], "millimetres");
  EXPECT_NEAR(j["hole_fraction"].get<double>(), 0.0207, 0.0005);
  GF_REQUIRE_DATASET(noisy, "icl_livingroom1_noisy5");
  EXPECT_NEAR(InputInfo(noisy, {})["hole_fraction"].get<double>(), 0.1271, 0.0005);
}

TEST(Info, MissingInputIsAnInputError) {
  EXPECT_THROW(InputInfo("/nonexistent/folder", {}), InputError);
}

}  // namespace
}  // namespace gf
