// FitRevolutions: clear objects completed as surfaces of revolution from the part the sensor read.
#include "surfels/revolution.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "surfels/revolution_outline_scene.h"

namespace gf {
namespace {

constexpr uint8_t kTransparent = static_cast<uint8_t>(DepthSource::kTransparent);

Surfel At(const Eigen::Vector3f& position, const Eigen::Vector3f& normal,
          uint8_t source = kTransparent) {
  Surfel s;
  s.position = position;
  s.normal = normal.normalized();
  s.radius = 0.003f;
  s.confidence = 4;
  s.source = source;
  return s;
}

// Surfels on the front `arc_deg` of a surface of revolution about `axis` through `base`, radius
// radius(h), with 1 mm of noise on positions and about 5 degrees on normals.
template <typename Radius>
std::vector<Surfel> FrontOf(const Eigen::Vector3f& base, const Eigen::Vector3f& axis, double height,
                            double arc_deg, Radius radius, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 0.001f), tilt(0.f, 0.08f);
  const Eigen::Vector3f u = axis.unitOrthogonal(), w = axis.cross(u);
  std::vector<Surfel> out;
  for (double h = 0; h <= height; h += 0.006)
    for (double a = -arc_deg / 2; a <= arc_deg / 2; a += 4) {
      const double t = a * M_PI / 180;
      const Eigen::Vector3f radial =
          static_cast<float>(std::cos(t)) * u + static_cast<float>(std::sin(t)) * w;
      const Eigen::Vector3f p = base + static_cast<float>(h) * axis +
                                static_cast<float>(radius(h)) * radial +
                                Eigen::Vector3f(noise(rng), noise(rng), noise(rng));
      out.push_back(At(p, radial + Eigen::Vector3f(tilt(rng), tilt(rng), tilt(rng))));
    }
  return out;
}

// Distance of p from the surface of revolution (axis through base, radius(h)).
template <typename Radius>
double OffSurface(const Eigen::Vector3f& p, const Eigen::Vector3f& base,
                  const Eigen::Vector3f& axis, Radius radius) {
  const Eigen::Vector3f d = p - base;
  const double h = axis.dot(d);
  return std::abs((d - static_cast<float>(h) * axis).norm() - radius(h));
}

TEST(Revolution, CompletesAGlassAllRoundFromItsFront) {
  const Eigen::Vector3f base(0.2f, -0.1f, 1.2f),
      axis = Eigen::Vector3f(0.1f, -1.f, 0.2f).normalized();
  auto radius = [](double) { return 0.04; };
  std::vector<Surfel> map = FrontOf(base, axis, 0.12, 90, radius, 1);
  map.push_back(At({1, 1, 1}, {0, 0, 1}, static_cast<uint8_t>(DepthSource::kSensor)));
  const RevolutionResult r = FitRevolutions(map, {});
  ASSERT_EQ(r.shapes.size(), 1u);
  const RevolutionShape& shape = r.shapes[0];
  EXPECT_GT(std::abs(shape.axis.dot(axis)), std::cos(3 * M_PI / 180));
  for (float rr : shape.radius_m) EXPECT_NEAR(rr, 0.04, 0.004);
  EXPECT_NEAR(shape.height_m, 0.12, 0.01);
  EXPECT_NEAR(shape.arc_deg, 90, 10);
  // Laid all round (the back too), on the true surface, transparent.
  ASSERT_GT(r.surfels.size(), 500u);
  int behind = 0;
  for (const Surfel& s : r.surfels) {
    EXPECT_EQ(s.source, kTransparent);
    EXPECT_LT(OffSurface(s.position, base, axis, radius), 0.005);
    behind += (s.position - base).dot(axis.unitOrthogonal()) < 0;
  }
  EXPECT_GT(behind, static_cast<int>(r.surfels.size()) / 3);
}

TEST(Revolution, FollowsABottleIntoItsNeck) {
  const Eigen::Vector3f base(0, 0.3f, 1.0f), axis(0, -1, 0);
  auto radius = [](double h) {  // a body, a shoulder, a neck
    return h < 0.11 ? 0.04 : h < 0.14 ? 0.04 - (h - 0.11) / 0.03 * 0.025 : 0.015;
  };
  const RevolutionResult r = FitRevolutions(FrontOf(base, axis, 0.2, 120, radius, 2), {});
  ASSERT_EQ(r.shapes.size(), 1u);
  const RevolutionShape& shape = r.shapes[0];
  ASSERT_GE(shape.radius_m.size(), 18u);
  std::vector<float> up = shape.radius_m;  // from the bottle's base (the axis may point down)
  if (shape.axis.dot(axis) < 0) std::reverse(up.begin(), up.end());
  EXPECT_NEAR(up[3], 0.04, 0.004);
  EXPECT_NEAR(up[up.size() - 3], 0.015, 0.004);
  int off = 0;
  for (const Surfel& s : r.surfels) off += OffSurface(s.position, base, axis, radius) > 0.006;
  EXPECT_LT(off, static_cast<int>(r.surfels.size()) / 10);  // on the shoulder, at most
}

TEST(Revolution, LeavesPanesSpheresAndScrapsAlone) {
  std::vector<Surfel> map;
  // A pane: every normal alike.
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) map.push_back(At({0.005f * i, 0.005f * j, 1.0f}, {0, 0, -1}));
  // A sphere's front: normals in every direction.
  for (int i = -6; i <= 6; ++i)
    for (int j = -6; j <= 6; ++j) {
      const Eigen::Vector3f n(0.12f * i, 0.12f * j, -1.f);
      map.push_back(At(Eigen::Vector3f(0.5f, 0, 1.2f) + 0.07f * n.normalized(), n));
    }
  // A few transparent surfels on an outline (fewer than min_surfels).
  for (int i = 0; i < 6; ++i) map.push_back(At({-0.5f, 0.01f * i, 1.0f}, {1, 0, -1}));
  const RevolutionResult r = FitRevolutions(map, {});
  EXPECT_EQ(r.objects, 2);
  EXPECT_TRUE(r.shapes.empty());
  EXPECT_TRUE(r.surfels.empty());
}

// Opaque surfels every 1 cm on a square of `half` metres round `centre` in the plane spanned by
// u and w (a table, a shelf board, a wall), normal u x w.
std::vector<Surfel> Board(const Eigen::Vector3f& centre, const Eigen::Vector3f& u,
                          const Eigen::Vector3f& w, float half) {
  std::vector<Surfel> out;
  const uint8_t sensor = static_cast<uint8_t>(DepthSource::kSensor);
  for (float a = -half; a <= half; a += 0.01f)
    for (float b = -half; b <= half; b += 0.01f)
      out.push_back(At(centre + a * u + b * w, u.cross(w), sensor));
  return out;
}

// A glass on a table seen over its middle only (the sensor missed its foot and its rim), the
// table tilted and a wall 6 cm behind the glass: the glass stands on the table, its axis the
// table's normal, its surface laid down to the table.
TEST(Revolution, StandsAGlassOnItsTable) {
  const Eigen::Vector3f up = Eigen::Vector3f(0.05f, -1.f, 0.1f).normalized();
  const Eigen::Vector3f across = up.unitOrthogonal(), depth = up.cross(across);
  const Eigen::Vector3f foot(0.1f, 0.4f, 1.3f);
  auto radius = [](double) { return 0.035; };
  std::vector<Surfel> map = FrontOf(Eigen::Vector3f(foot + 0.05f * up), up, 0.08, 100, radius, 3);
  for (Surfel& s : map) {  // the front faces the camera (-depth): turn the arc towards it
    const Eigen::Vector3f d = s.position - foot;
    s.position = foot + d.dot(up) * up +
                 Eigen::AngleAxisf(static_cast<float>(M_PI) / 2, up) * (d - d.dot(up) * up);
    s.normal = Eigen::AngleAxisf(static_cast<float>(M_PI) / 2, up) * s.normal;
  }
  const std::vector<Surfel> table = Board(foot, across, depth, 0.25f);
  const std::vector<Surfel> wall = Board(foot + 0.1f * depth + 0.15f * up, across, up, 0.2f);
  map.insert(map.end(), table.begin(), table.end());
  map.insert(map.end(), wall.begin(), wall.end());
  const RevolutionResult r = FitRevolutions(map, {});
  ASSERT_EQ(r.shapes.size(), 1u);
  const RevolutionShape& shape = r.shapes[0];
  EXPECT_TRUE(shape.standing);
  EXPECT_GT(shape.axis.dot(up), std::cos(1 * M_PI / 180));
  EXPECT_NEAR(shape.height_m, 0.13, 0.01);
  EXPECT_LT((shape.base - foot).norm(), 0.005);
  float lowest = 1;
  for (const Surfel& s : r.surfels) {
    EXPECT_LT(OffSurface(s.position, foot, up, radius), 0.005);
    lowest = std::min(lowest, (s.position - foot).dot(up));
  }
  EXPECT_LT(lowest, 0.005);
  // Off: the axis from the normals, the surface only where the glass was read.
  RevolutionOptions off;
  off.stand_on_support = false;
  const RevolutionResult r2 = FitRevolutions(map, off);
  ASSERT_EQ(r2.shapes.size(), 1u);
  EXPECT_FALSE(r2.shapes[0].standing);
  EXPECT_NEAR(r2.shapes[0].height_m, 0.08, 0.01);
}

// A bottle whose label (opaque, 10 cm) the sensor reads, its glass seen through only above the
// label (14 cm up) and read as an opaque surface below it: the bottle is one object standing on
// the table, fitted to its glass and its label. A second glass 4 cm away stays apart, and so does
// a glass on the board above.
TEST(Revolution, FitsABottleWithItsLabel) {
  const Eigen::Vector3f up(0, -1, 0), foot(0, 0.4f, 1.3f);
  auto radius = [](double) { return 0.03; };
  std::vector<Surfel> map;
  for (double h0 : {0.02, 0.14}) {  // the glass below and above the label, a narrow strip
    std::vector<Surfel> glass =
        FrontOf(Eigen::Vector3f(foot + static_cast<float>(h0) * up), up, 0.015, 40, radius, 4);
    if (h0 < 0.1)
      for (Surfel& s : glass) s.source = static_cast<uint8_t>(DepthSource::kSensor);
    map.insert(map.end(), glass.begin(), glass.end());
  }
  std::vector<Surfel> label = FrontOf(Eigen::Vector3f(foot + 0.035f * up), up, 0.1, 120, radius, 5);
  for (Surfel& s : label) s.source = static_cast<uint8_t>(DepthSource::kSensor);
  map.insert(map.end(), label.begin(), label.end());
  const Eigen::Vector3f other(0.1f, 0.4f, 1.3f);  // a second glass, 4 cm from the first
  const std::vector<Surfel> glass2 = FrontOf(other, up, 0.1, 120, radius, 6);
  map.insert(map.end(), glass2.begin(), glass2.end());
  const Eigen::Vector3f above(0, 0.1f, 1.3f);  // on a board 30 cm up, over the bottle
  const std::vector<Surfel> glass3 = FrontOf(above, up, 0.1, 120, radius, 7);
  map.insert(map.end(), glass3.begin(), glass3.end());
  for (const Eigen::Vector3f& board : {foot, above}) {
    const std::vector<Surfel> b = Board(board + Eigen::Vector3f(0, 0, 0.05f),
                                        Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(1, 0, 0), 0.2f);
    map.insert(map.end(), b.begin(), b.end());
  }
  const RevolutionResult r = FitRevolutions(map, {});
  EXPECT_EQ(r.objects, 3);
  ASSERT_EQ(r.shapes.size(), 3u);
  int bottles = 0;
  for (const RevolutionShape& shape : r.shapes) {
    EXPECT_TRUE(shape.standing);
    EXPECT_GT(shape.axis.dot(up), 0.999f);
    for (float rr : shape.radius_m) EXPECT_NEAR(rr, 0.03, 0.004);
    bottles += std::abs(shape.height_m - 0.155f) < 0.01f;
  }
  EXPECT_EQ(bottles, 1);  // from the table to the top of the upper glass
  // Its transparent surfels alone (a narrow strip high above the table): no shape for the bottle.
  RevolutionOptions alone;
  alone.fit_whole_surface = false;
  EXPECT_EQ(FitRevolutions(map, alone).shapes.size(), 2u);
}

// A vase seen from the front over a narrow strip (30 degrees of its 4.5 cm radius, 1.5 mm of
// noise: a plane fits it as well as a circle) stands on a table before a textured wall: refused
// from its surfels alone, it takes its radius from its outline in colour views.
TEST(Revolution, TakesAVaseRadiusFromItsOutline) {
  using test_scene::kGlassHeight;
  using test_scene::kGlassRadius;
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.f, 0.0015f), tilt(0.f, 0.08f);
  std::vector<Surfel> map;
  for (double h = 0.02; h <= kGlassHeight - 0.02; h += 0.006)
    for (double a = -15; a <= 15; a += 3) {
      const double t = (a - 90) * M_PI / 180;  // around -y, towards the cameras
      const Eigen::Vector3f radial(static_cast<float>(std::cos(t)),
                                   static_cast<float>(std::sin(t)), 0.f);
      const Eigen::Vector3f p = static_cast<float>(kGlassRadius) * radial +
                                Eigen::Vector3f(noise(rng), noise(rng), static_cast<float>(h));
      map.push_back(At(p, radial + Eigen::Vector3f(tilt(rng), tilt(rng), tilt(rng))));
    }
  const uint8_t sensor = static_cast<uint8_t>(DepthSource::kSensor);
  for (float x = -0.3f; x <= 0.3f; x += 0.01f) {
    for (float y = -0.3f; y < 0.15f; y += 0.01f)
      if (std::hypot(x, y) > kGlassRadius + 0.01) map.push_back(At({x, y, 0.f}, {0, 0, 1}, sensor));
    for (float z = 0.f; z <= 0.3f; z += 0.01f)
      map.push_back(At({x, static_cast<float>(test_scene::kWallY), z}, {0, -1, 0}, sensor));
  }
  const RevolutionResult alone = FitRevolutions(map, {});
  EXPECT_TRUE(alone.shapes.empty());
  const Camera camera = test_scene::SmallCamera();
  const std::vector<SE3> poses = test_scene::Views();
  const OutlineViews views = [&](size_t i, OutlineView* view) {
    if (i >= poses.size()) return false;
    *view = {test_scene::Render(camera, poses[i], true), poses[i]};
    return true;
  };
  const RevolutionResult r = FitRevolutions(map, {}, &camera, views);
  ASSERT_EQ(r.shapes.size(), 1u);
  const RevolutionShape& shape = r.shapes[0];
  EXPECT_TRUE(shape.standing && shape.from_outline);
  EXPECT_NEAR(shape.radius_m.front(), kGlassRadius, 0.003);
  EXPECT_LT(Eigen::Vector2f(shape.base.x(), shape.base.y()).norm(), 0.005);
  for (const Surfel& s : r.surfels)
    EXPECT_NEAR(Eigen::Vector2f(s.position.x(), s.position.y()).norm(), kGlassRadius, 0.004);
  // Off: left as it is.
  RevolutionOptions off;
  off.fit_outline = false;
  EXPECT_TRUE(FitRevolutions(map, off, &camera, views).shapes.empty());
}

TEST(Revolution, OptionsAreChecked) {
  EXPECT_TRUE(RevolutionOptions().Check());
  RevolutionOptions o;
  o.min_radius_m = 0.3;
  std::string problem;
  EXPECT_FALSE(o.Check(&problem));
  EXPECT_NE(problem.find("min_radius_m"), std::string::npos) << problem;
  o = {};
  o.spacing_m = 0;
  EXPECT_FALSE(o.Check(&problem));
  o = {};
  o.min_edge_ratio = 0;
  EXPECT_FALSE(o.Check(&problem));
  EXPECT_NE(problem.find("min_edge_ratio"), std::string::npos) << problem;
}

}  // namespace
}  // namespace gf
