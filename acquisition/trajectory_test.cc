#include "acquisition/trajectory.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "acquisition/errors.h"
#include "tests/testing.h"

namespace gf {
namespace {

Trajectory RandomTrajectory(int n) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0, 1);
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    StampedPose p;
    p.timestamp = 1305031102.160407 + 0.033 * i;
    SE3::Tangent xi;
    xi << g(rng), g(rng), g(rng), g(rng), g(rng), g(rng);
    p.world_from_camera = SE3::Exp(xi);
    t.push_back(p);
  }
  return t;
}

TEST(TumTrajectory, WriteReadRoundTrip) {
  testing::TempDir dir;
  Trajectory t = RandomTrajectory(50);
  t[3].timestamp = 1305031102.194330;
  t[3].timestamp_text = "1305031102.194330";  // kept verbatim, trailing zero included
  WriteTumTrajectory(dir / "traj.txt", t);
  const Trajectory r = ReadTumTrajectory(dir / "traj.txt");
  ASSERT_EQ(r.size(), t.size());
  EXPECT_EQ(r[3].timestamp_text, "1305031102.194330");
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(r[i].timestamp, t[i].timestamp, 1e-6);
    EXPECT_LT((r[i].world_from_camera.Matrix() - t[i].world_from_camera.Matrix()).norm(), 1e-7);
  }
}

TEST(TumTrajectory, ReadsTheTumGroundTruth) {
  GF_REQUIRE_DATASET(tum, "tum_fr1_xyz_head");
  const Trajectory t = ReadTumTrajectory(tum + "/groundtruth.txt");
  EXPECT_EQ(t.size(), 698u);
  EXPECT_EQ(t[0].timestamp_text, "1305031101.1659");
  EXPECT_LT((t[0].world_from_camera.translation() - Eigen::Vector3d(1.38, 0.6185, 1.6972)).norm(),
            1e-9);
  EXPECT_NEAR(t[0].world_from_camera.rotation().w(), 0.3236, 1e-4);  // sign-normalised (w >= 0)
}

TEST(TumTrajectory, MalformedLinesNameFileAndLine) {
  testing::TempDir dir;
  const std::string path = dir / "bad.txt";
  std::ofstream(path) << "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0\n";
  try {
    ReadTumTrajectory(path);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": line 3"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "# only comments\n";
  EXPECT_THROW(ReadTumTrajectory(path), InputError);
  std::ofstream(path) << "1.0 0 0 0 0 0 0 3\n";
  EXPECT_THROW(ReadTumTrajectory(path), InputError);  // not a unit quaternion
}

TEST(RedwoodLog, ReadsIclGroundTruth) {
  GF_REQUIRE_DATASET(icl, "icl_livingroom1_micro");
  const Trajectory t = ReadRedwoodLog(icl + "/groundtruth.log");
  ASSERT_EQ(t.size(), 211u);
  EXPECT_EQ(t[0].timestamp, 0.0);
  EXPECT_EQ(t[210].timestamp, 210.0);
  EXPECT_LT((t[0].world_from_camera.translation() -
             Eigen::Vector3d(-0.31057997014702826, 0.5730122438481298, 2.1264800183565487))
                .norm(),
            1e-12);
  // Consecutive frames of a handheld trajectory move a few millimetres.
  EXPECT_LT((t[1].world_from_camera.translation() - t[0].world_from_camera.translation()).norm(),
            0.05);
}

TEST(RedwoodLog, WriteReadRoundTripAndTruncation) {
  testing::TempDir dir;
  Trajectory t = RandomTrajectory(10);
  for (size_t i = 0; i < t.size(); ++i) t[i].timestamp = static_cast<double>(i);
  WriteRedwoodLog(dir / "t.log", t);
  const Trajectory r = ReadTrajectory(dir / "t.log");
  ASSERT_EQ(r.size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(r[i].timestamp, static_cast<double>(i));
    EXPECT_LT((r[i].world_from_camera.Matrix() - t[i].world_from_camera.Matrix()).norm(), 1e-10);
  }
  std::ofstream(dir / "cut.log") << "0 0 1\n1 0 0 0\n0 1 0 0\n";
  EXPECT_THROW(ReadRedwoodLog(dir / "cut.log"), InputError);
}

}  // namespace
}  // namespace gf
