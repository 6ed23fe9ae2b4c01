#include "acquisition/bounds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "acquisition/depth.h"
#include "acquisition/frame_sink.h"
#include "acquisition/frame_source.h"
#include "acquisition/trajectory_metrics.h"

namespace gf {
namespace {

struct Inner {
  int window_px = 5;
  bool Check(std::string* message) const {
    FieldCheck c(message);
    c.In("window_px", window_px, 1, kMaxImageSidePx, kLargerThanAnyImage);
    return c.ok();
  }
};

TEST(FieldCheck, NamesTheFirstFieldOutsideItsRange) {
  std::string message;
  FieldCheck ok(&message);
  ok.In("a", 3, 1, 5, "is too much").Above("b", 0.5, 0, 1, kMoreThanOne);
  EXPECT_TRUE(ok.ok());
  EXPECT_EQ(message, "");

  FieldCheck high(&message);
  high.In("a", 30000, 1, kMaxImageSidePx, kLargerThanAnyImage).In("b", -1, 0, 1, kMoreThanOne);
  EXPECT_FALSE(high.ok());
  EXPECT_EQ(message, "a 30000 is larger than any image (at most 4096)");

  FieldCheck low(&message);
  low.In("a", 0, 1, 5, "is too much");
  EXPECT_EQ(message, "a 0 must be at least 1");
  FieldCheck open(&message);
  open.Above("b", 0, 0, 1, kMoreThanOne);
  EXPECT_EQ(message, "b 0 must be more than 0");
  FieldCheck nan(&message);
  nan.Above("b", std::nan(""), 0, 1, kMoreThanOne);
  EXPECT_EQ(message, "b is not a number");
  FieldCheck inf(&message);
  inf.In("c", INFINITY, 0, 1e6, "is too much");
  EXPECT_EQ(message, "c inf is too much (at most 1000000)");
  FieldCheck big(&message);
  big.In("d", 1e12, 0, 0.5, kMoreThanOne);
  EXPECT_EQ(message, "d 1e+12 is more than one (at most 0.5)");
}

TEST(FieldCheck, ListsAndPartsNameTheirPlace) {
  std::string message;
  FieldCheck list(&message);
  list.Each("iterations", {10, 2000000000, 2}, 0, kMaxIterations, kMoreIterationsThanAFrameAllows);
  EXPECT_EQ(message,
            "iterations[1] 2000000000 is more iterations than a frame's time allows (at most "
            "1000)");
  FieldCheck empty(&message);
  empty.Each("iterations", {}, 0, 10, "is too much");
  EXPECT_EQ(message, "iterations must list at least one value");

  Inner inner;
  FieldCheck part(&message);
  EXPECT_TRUE(part.Part("inner", inner).ok());
  inner.window_px = 5000;
  part.Part("inner", inner).Require(false, "never reached");
  EXPECT_FALSE(part.ok());
  EXPECT_EQ(message, "inner.window_px 5000 is larger than any image (at most 4096)");
  FieldCheck require(&message);
  require.Require(true, "fine").Require(false, "max_depth_m must be more than min_depth_m");
  EXPECT_EQ(message, "max_depth_m must be more than min_depth_m");
  FieldCheck silent(nullptr);  // no message wanted
  EXPECT_FALSE(silent.In("a", 9, 0, 1, "is too much").ok());
}

// The acquisition layer's own Options refuse a bad value naming the field and the value.
TEST(FieldCheck, AcquisitionOptionsNameTheFieldTheyRefuse) {
  std::string problem;
  DepthConversionOptions depth;
  depth.min_depth_m = 3;
  depth.max_depth_m = 2;
  EXPECT_FALSE(depth.Check(&problem));
  EXPECT_EQ(problem, "max_depth_m must be more than min_depth_m");
  TumFolderSinkOptions sink;
  sink.depth_scale = 1e6;
  EXPECT_FALSE(sink.Check(&problem));
  EXPECT_EQ(problem.rfind("depth_scale 1000000 leaves no room for half a metre", 0), 0u) << problem;
  FrameSourceOptions source;
  source.shadows.min_relative_jump = -1;
  EXPECT_FALSE(source.Check(&problem));
  EXPECT_EQ(problem.rfind("shadows.min_relative_jump -1 ", 0), 0u) << problem;
  source = FrameSourceOptions();
  source.max_association_dt_s = 5;
  EXPECT_FALSE(source.Check(&problem));
  EXPECT_EQ(problem, "max_association_dt_s 5 is more than a second (at most 1)");
  EXPECT_TRUE(FrameSourceOptions().Check(&problem)) << problem;
  EXPECT_TRUE(TumFolderSinkOptions().Check(&problem)) << problem;
  EXPECT_TRUE(TrajectoryErrorOptions().Check(&problem)) << problem;
}

}  // namespace
}  // namespace gf
