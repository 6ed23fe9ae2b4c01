#include "surfels/mesh.h"

#include <pcl/PolygonMesh.h>
#include <pcl/common/io.h>
#include <pcl/io/ply_io.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/surface/gp3.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/bounds.h"

namespace gf {

bool MeshOptions::Check(std::string* message) const {
  // A triangle needs 3 neighbours; each is a point of the map (at most kMaxMapSurfels).
  FieldCheck c(message);
  c.Above("search_radius_m", search_radius_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("neighbour_factor", neighbour_factor, 0, kMaxSceneM,
             "makes a search radius larger than any scene")
      .In("max_neighbours", max_neighbours, 3, kMaxImagePixels, kMoreThanAnImagesPixels);
  return c.ok();
}

std::string MeshSummary::BriefReport() const {
  char buffer[120];
  std::snprintf(buffer, sizeof(buffer), "mesh: %ld vertices, %ld faces in %.1f s", vertices, faces,
                seconds);
  return buffer;
}

MeshSummary WriteMapMesh(const std::vector<Surfel>& surfels, const std::string& path,
                         const MeshOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  const auto start = std::chrono::steady_clock::now();
  pcl::PointCloud<pcl::PointXYZRGBNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGBNormal>);
  for (const Surfel& s : surfels) {
    if (s.removed()) continue;
    pcl::PointXYZRGBNormal p;
    p.x = s.position.x(), p.y = s.position.y(), p.z = s.position.z();
    p.normal_x = s.normal.x(), p.normal_y = s.normal.y(), p.normal_z = s.normal.z();
    p.r = s.red, p.g = s.green, p.b = s.blue;
    cloud->push_back(p);
  }
  pcl::PolygonMesh mesh;
  if (cloud->size() >= 3) {
    pcl::search::KdTree<pcl::PointXYZRGBNormal>::Ptr tree(
        new pcl::search::KdTree<pcl::PointXYZRGBNormal>);
    tree->setInputCloud(cloud);
    pcl::GreedyProjectionTriangulation<pcl::PointXYZRGBNormal> gp3;
    gp3.setSearchRadius(options.search_radius_m);
    gp3.setMu(options.neighbour_factor);
    gp3.setMaximumNearestNeighbors(options.max_neighbours);
    gp3.setMaximumSurfaceAngle(M_PI / 4);
    gp3.setMinimumAngle(M_PI / 18);
    gp3.setMaximumAngle(2 * M_PI / 3);
    gp3.setNormalConsistency(true);
    gp3.setInputCloud(cloud);
    gp3.setSearchMethod(tree);
    gp3.reconstruct(mesh);
  } else {
    pcl::toPCLPointCloud2(*cloud, mesh.cloud);
  }
  WriteFileAtomically(path, [&](const std::string& temporary) {
    if (pcl::io::savePLYFileBinary(temporary, mesh) != 0)
      throw InputError(path, "cannot write the mesh");
  });
  MeshSummary s;
  s.vertices = static_cast<long>(mesh.cloud.width) * mesh.cloud.height;
  s.faces = static_cast<long>(mesh.polygons.size());
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

}  // namespace gf
