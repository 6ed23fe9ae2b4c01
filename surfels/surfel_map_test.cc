// The surfel map's storage (blocks, compaction, moves) and its PLY file read back by PCL.
#include "surfels/surfel_map.h"

#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>

#include <string>
#include <vector>

#include "acquisition/errors.h"
#include "surfels/ply.h"
#include "tests/testing.h"

namespace gf {
namespace {

// n live surfels, each with last_frame its index (which identifies it after compaction).
SurfelMap NumberedMap(int n) {
  SurfelMap map;
  for (int i = 0; i < n; ++i) {
    Surfel s;
    s.position = s.normal = Eigen::Vector3f::Zero();
    s.confidence = 1;
    s.last_frame = i;
    map.Add(s);
  }
  return map;
}

TEST(SurfelMap, CompactionCostsNothingForOldSurfelsBeforeTheFirstRemovedOne) {
  SurfelMap map = NumberedMap(1000);
  // One removed among the last 20: more than a tenth of the surfels compaction would move.
  map.Remove(990);
  EXPECT_EQ(map.Compact(0.1), 990u);
  ASSERT_EQ(map.size(), 999u);
  EXPECT_EQ(map[990].last_frame, 991);
  EXPECT_EQ(map[989].last_frame, 989);
  // One removed near the start: a tiny share of what would move, so nothing moves yet...
  map.Remove(10);
  EXPECT_EQ(map.Compact(0.1), map.size());
  EXPECT_TRUE(map[10].removed());
  EXPECT_EQ(map.live(), 998u);
  // ... until the removed ones are a tenth of it.
  for (size_t i = 100; i < 200; ++i) map.Remove(i);
  EXPECT_EQ(map.Compact(0.1), 10u);
  ASSERT_EQ(map.size(), 898u);
  EXPECT_EQ(map.live(), 898u);
  EXPECT_EQ(map[10].last_frame, 11);
  EXPECT_EQ(map[99].last_frame, 200);
}

TEST(SurfelMap, KeepsOrderAcrossItsBlocksWhenItCompactsAndGrowsAgain) {
  // 150000 surfels span three storage blocks; every third one from 50000 on is removed.
  SurfelMap map = NumberedMap(150000);
  for (size_t i = 50000; i < map.size(); i += 3) map.Remove(i);
  EXPECT_EQ(map.Compact(0.1), 50000u);
  ASSERT_EQ(map.size(), 150000u - 33334u);
  EXPECT_EQ(map.live(), map.size());
  std::vector<int> expected;
  for (int i = 0; i < 150000; ++i)
    if (i < 50000 || (i - 50000) % 3 != 0) expected.push_back(i);
  bool same = true;
  for (size_t i = 0; i < map.size(); ++i) same &= map[i].last_frame == expected[i];
  EXPECT_TRUE(same);
  const size_t bytes = map.MemoryBytes();
  // It grows again into the blocks it kept, then into a new one.
  for (int i = 0; i < 100000; ++i) map.Add(map[i]);
  EXPECT_EQ(map.size(), expected.size() + 100000u);
  EXPECT_EQ(map[expected.size()].last_frame, 0);
  EXPECT_EQ(map[map.size() - 1].last_frame, expected[99999]);
  EXPECT_GT(map.MemoryBytes(), bytes);
  EXPECT_EQ(map.ToVector().size(), map.size());
}

// A map moved from is empty and usable; a removed surfel added to a map counts as removed.
TEST(SurfelMap, AMovedFromMapIsEmptyAndRemovedSurfelsAddedCount) {
  SurfelMap map = NumberedMap(10);
  const Surfel s = map[0];
  map.Remove(3);
  SurfelMap moved = std::move(map);
  EXPECT_EQ(moved.size(), 10u);
  EXPECT_EQ(moved.live(), 9u);
  EXPECT_EQ(map.size(), 0u);  // NOLINT(bugprone-use-after-move): defined as empty
  map.Add(s);
  EXPECT_EQ(map.live(), 1u);
  SurfelMap copy;
  for (const Surfel& t : moved.ToVector()) copy.Add(t);
  EXPECT_EQ(copy.live(), 9u);
  EXPECT_EQ(copy.Compact(0.1), 3u);
  EXPECT_EQ(copy.size(), 9u);
}

TEST(SurfelPly, RoundTrip) {
  testing::TempDir dir;
  std::vector<Surfel> surfels(3);
  for (int i = 0; i < 3; ++i) {
    surfels[i].position = Eigen::Vector3f(i, 2.f * i, -1.f);
    surfels[i].normal = Eigen::Vector3f(0, 0, 1);
    surfels[i].radius = 0.004f * (i + 1);
    surfels[i].confidence = 12.5f;
    surfels[i].red = 10, surfels[i].green = 20, surfels[i].blue = static_cast<uint8_t>(30 + i);
    surfels[i].source = static_cast<uint8_t>(i == 2 ? DepthSource::kStereo : DepthSource::kSensor);
  }
  WriteSurfelPly(dir / "map.ply", surfels);
  const std::vector<Surfel> back = ReadSurfelPly(dir / "map.ply");
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].position, surfels[i].position);
    EXPECT_EQ(back[i].normal, surfels[i].normal);
    EXPECT_EQ(back[i].radius, surfels[i].radius);
    EXPECT_EQ(back[i].confidence, surfels[i].confidence);
    EXPECT_EQ(back[i].blue, surfels[i].blue);
    EXPECT_EQ(back[i].source, surfels[i].source);
  }
  EXPECT_THROW(ReadSurfelPly(dir / "missing.ply"), InputError);
  // PCL reads it with every field (it packs red, green and blue into one rgb field).
  pcl::PCLPointCloud2 cloud;
  ASSERT_EQ(pcl::io::loadPLYFile(dir / "map.ply", cloud), 0);
  EXPECT_EQ(cloud.width * cloud.height, 3u);
  std::vector<std::string> names;
  for (const auto& f : cloud.fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "normal_x", "normal_y", "normal_z",
                                             "rgb", "radius", "confidence", "source"}));
}

}  // namespace
}  // namespace gf
