#include "surfels/mesh.h"

#include <gtest/gtest.h>
#include <pcl/PolygonMesh.h>
#include <pcl/io/ply_io.h>

#include "tests/testing.h"

namespace gf {
namespace {

// A 0.5 m square of surfels 5 mm apart meshes into triangles between neighbours, and PCL reads the
// mesh back.
TEST(WriteMapMesh, TrianglesASquareOfSurfels) {
  testing::TempDir dir;
  std::vector<Surfel> square;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j) {
      Surfel s;
      s.position = Eigen::Vector3f(0.005f * i, 0.005f * j, 1.f);
      s.normal = Eigen::Vector3f(0, 0, -1);
      s.radius = 0.004f;
      square.push_back(s);
    }
  const MeshSummary m = WriteMapMesh(square, dir / "mesh.ply", {});
  EXPECT_EQ(m.vertices, 10000);
  // A full triangulation of a 100 x 100 grid has 2 * 99 * 99 = 19602 triangles.
  EXPECT_GT(m.faces, 15000);
  pcl::PolygonMesh back;
  ASSERT_EQ(pcl::io::loadPLYFile(dir / "mesh.ply", back), 0);
  EXPECT_EQ(static_cast<long>(back.polygons.size()), m.faces);
  EXPECT_EQ(static_cast<long>(back.cloud.width) * back.cloud.height, 10000);
}

}  // namespace
}  // namespace gf
