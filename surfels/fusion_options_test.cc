#include <gtest/gtest.h>

#include <string>

#include "acquisition/bounds.h"
#include "surfels/fusion.h"

namespace gf {
namespace {

// The map's budget is bounded by memory (16 GiB of surfels), and the other settings by theirs.
TEST(FusionOptions, RefusesValuesBeyondTheirBounds) {
  FusionOptions o;
  std::string message;
  EXPECT_TRUE(o.Check(&message)) << message;
  o.max_surfels = kMaxMapSurfels;
  EXPECT_TRUE(o.Check(&message)) << message;
  o.max_surfels = kMaxMapSurfels + 1;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_EQ(message.rfind("max_surfels ", 0), 0u) << message;
  o = {};
  o.normal_filter_px = 30000;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_EQ(message, "normal_filter_px 30000 is larger than any half-size image (at most 2048)");
  o = {};
  o.max_depth_m = 1e12;
  EXPECT_FALSE(o.Check(&message));
  EXPECT_EQ(message.rfind("max_depth_m 1e+12 is farther than any sensor measures", 0), 0u)
      << message;
}

}  // namespace
}  // namespace gf
