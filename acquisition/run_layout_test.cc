#include "acquisition/run_layout.h"

#include <gtest/gtest.h>

namespace gf {
namespace {

TEST(RunLayout, NamesEveryKeyframeImageAndReadsTheNameBack) {
  EXPECT_EQ(RunLayout::Keyframe("1305031102.175304", KeyframeImage::kDepthFilled),
            "keyframes/1305031102.175304.depth_filled.png");
  for (KeyframeImage image :
       {KeyframeImage::kHoleMask, KeyframeImage::kDepthFilled, KeyframeImage::kFillConfidence,
        KeyframeImage::kFillOverlay, KeyframeImage::kColor, KeyframeImage::kModelFill,
        KeyframeImage::kGlassMask}) {
    const std::string file = RunLayout::Keyframe("12.5", image).substr(10);  // after keyframes/
    EXPECT_EQ(RunLayout::KeyframeOf(file, image), "12.5") << file;
  }
  // Another image of the same keyframe, or a name that is only the suffix, is not it.
  EXPECT_EQ(RunLayout::KeyframeOf("12.5.fill_overlay.png", KeyframeImage::kColor), "");
  EXPECT_EQ(RunLayout::KeyframeOf(".color.png", KeyframeImage::kColor), "");
}

TEST(RunLayout, ComparesRunFoldersSitInsideTheComparison) {
  const RunLayout cmp("/tmp/cmp");
  EXPECT_EQ(cmp.Map(true).Path(RunLayout::kMap), "/tmp/cmp/with_fill/map.ply");
  EXPECT_EQ(cmp.Map(false).Path("a", KeyframeImage::kHoleMask),
            "/tmp/cmp/without_fill/keyframes/a.hole_mask.png");
  EXPECT_EQ(RunLayout::Rendering(false, "above"), "without_fill_above.png");
  EXPECT_EQ(RunLayout::Undistorted("depth/000001_1.5.png"), "undistorted/depth/000001_1.5.png");
}

}  // namespace
}  // namespace gf
