// OutlineSearch: a clear glass's radius from its outline in rendered colour views.
#include "surfels/revolution_outline.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <vector>

#include "surfels/revolution_outline_scene.h"

namespace gf {
namespace {

using test_scene::kGlassRadius;

std::vector<OutlineFit> Search(bool glass, const std::vector<Eigen::Vector3d>& solid) {
  const Camera camera = test_scene::SmallCamera();
  OutlineSearch search({test_scene::FrontOfGlass(solid)}, camera, OutlineSearchOptions{});
  for (const SE3& pose : test_scene::Views())
    search.AddView({test_scene::Render(camera, pose, glass), pose});
  return search.Fits();
}

TEST(OutlineSearch, FindsAGlassRadiusFromItsOutline) {
  const std::vector<OutlineFit> fits = Search(true, test_scene::WallPoints());
  ASSERT_EQ(fits.size(), 1u);
  const OutlineFit& fit = fits[0];
  EXPECT_TRUE(fit.found) << "edge ratio " << fit.edge_ratio;
  EXPECT_NEAR(fit.radius_m, kGlassRadius, 0.003);
  // The axis is at the world's origin, kGlassRadius behind the strip's middle (the frame's origin).
  EXPECT_NEAR(fit.centre.x(), 0.0, 0.005);
  EXPECT_NEAR(fit.centre.y(), kGlassRadius, 0.005);
  EXPECT_GE(fit.views, 3);
}

TEST(OutlineSearch, FindsNoOutlineInATextureAlone) {
  const std::vector<OutlineFit> fits = Search(false, test_scene::WallPoints());
  ASSERT_EQ(fits.size(), 1u);
  EXPECT_FALSE(fits[0].found) << "radius " << fits[0].radius_m << " edge ratio "
                              << fits[0].edge_ratio;
}

TEST(OutlineSearch, RulesOutShapesThatHoldSomethingSolid) {
  // A post stands where the glass's axis is: no hypothesis as wide as the glass may hold it.
  std::vector<Eigen::Vector3d> solid = test_scene::WallPoints();
  for (double z = 0.02; z < 0.18; z += 0.01) solid.emplace_back(0.0, 0.0, z);
  const std::vector<OutlineFit> fits = Search(true, solid);
  ASSERT_EQ(fits.size(), 1u);
  EXPECT_FALSE(fits[0].found && std::abs(fits[0].radius_m - kGlassRadius) < 0.01)
      << "radius " << fits[0].radius_m;
}

}  // namespace
}  // namespace gf
