#include "surfels/completeness.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/bounds.h"

namespace gf {
namespace {

struct Samples {
  std::vector<Eigen::Vector3f> points;
  std::vector<uint8_t> material;
  std::vector<int> triangle;
};

// An even lattice of points on every triangle, `spacing` apart along its two edges from the
// first vertex.
Samples SampleMesh(const TriangleMesh& mesh, double spacing) {
  Samples s;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const float longest = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
    const int n = std::max(1, static_cast<int>(std::ceil(longest / spacing)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        s.points.push_back(a + (b - a) * (float(i) / n) + (c - a) * (float(j) / n));
        s.material.push_back(mesh.material.empty() ? 0 : mesh.material[t[0]]);
        s.triangle.push_back(static_cast<int>(f));
      }
  }
  return s;
}

// Which samples some view's true depth sees (within the relative tolerance at their pixel).
std::vector<uint8_t> Observed(const Samples& s, const Camera& camera,
                              const std::vector<TruthView>& views,
                              const CompletenessOptions& options) {
  std::vector<uint8_t> seen(s.points.size(), views.empty() ? 1 : 0);
  for (const TruthView& v : views) {
    const SE3 camera_from_world = v.world_from_camera.Inverse();
    for (size_t i = 0; i < s.points.size(); ++i) {
      if (seen[i]) continue;
      const Eigen::Vector3d q = camera_from_world * s.points[i].cast<double>();
      if (q.z() < options.min_depth_m || q.z() > options.max_depth_m) continue;
      const Eigen::Vector2d uv = camera.ProjectDistorted(q);
      const int x = static_cast<int>(std::lround(uv.x())),
                y = static_cast<int>(std::lround(uv.y()));
      if (x < 0 || y < 0 || x >= v.depth.cols || y >= v.depth.rows) continue;
      const float d = v.depth.at<float>(y, x);
      seen[i] = d > 0 && std::abs(d - q.z()) <= options.observed_tolerance * d;
    }
  }
  return seen;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr Cloud(const std::vector<Eigen::Vector3f>& points) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(points.size());
  for (const Eigen::Vector3f& p : points) cloud->push_back({p.x(), p.y(), p.z()});
  return cloud;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1))];
}

}  // namespace

bool CompletenessOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("sample_spacing_m", sample_spacing_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("observed_tolerance", observed_tolerance, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .Require(!within_m.empty(), "within_m needs at least one distance");
  for (size_t i = 0; i < within_m.size(); ++i)
    c.Above(("within_m[" + std::to_string(i) + "]").c_str(), within_m[i], 0, kMaxSceneM,
            kLargerThanAnyScene);
  c.In("min_depth_m", min_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_depth_m", max_depth_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Require(max_depth_m > min_depth_m, "max_depth_m must be more than min_depth_m");
  return c.ok();
}

std::string MapScore::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer),
                "%ld map points: accuracy median %.1f mm, p90 %.1f mm; %ld observed samples, "
                "%.1f%% within %s",
                map_points, 1000 * accuracy_median_m, 1000 * accuracy_p90_m, overall.observed,
                overall.within.empty() ? 0.0 : 100 * overall.within.back(), "the last threshold");
  return buffer;
}

MapScore ScoreMap(const std::vector<Surfel>& map, const TriangleMesh& mesh, const Camera& camera,
                  const std::vector<TruthView>& views, const CompletenessOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  MapScore score;
  const Samples samples = SampleMesh(mesh, options.sample_spacing_m);
  const std::vector<uint8_t> observed = Observed(samples, camera, views, options);
  std::vector<Eigen::Vector3f> map_points;
  for (const Surfel& s : map) map_points.push_back(s.position);
  score.map_points = static_cast<long>(map_points.size());
  const size_t thresholds = options.within_m.size();
  score.overall.within.assign(thresholds, 0);
  std::array<std::vector<long>, 256> hits;
  // Completeness: the nearest map point of every observed sample.
  if (!map_points.empty()) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(Cloud(map_points));
    std::vector<int> index(1);
    std::vector<float> d2(1);
    std::vector<long> overall(thresholds, 0);
    for (size_t i = 0; i < samples.points.size(); ++i) {
      if (!observed[i]) continue;
      const uint8_t m = samples.material[i];
      ++score.overall.observed;
      ++score.per_material[m].observed;
      if (hits[m].empty()) hits[m].assign(thresholds, 0);
      const Eigen::Vector3f& p = samples.points[i];
      if (tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, d2) < 1) continue;
      const double d = std::sqrt(d2[0]);
      for (size_t t = 0; t < thresholds; ++t)
        if (d <= options.within_m[t]) ++overall[t], ++hits[m][t];
    }
    for (size_t t = 0; t < thresholds; ++t)
      score.overall.within[t] =
          score.overall.observed ? double(overall[t]) / score.overall.observed : 0.0;
  } else {
    for (size_t i = 0; i < samples.points.size(); ++i)
      if (observed[i]) ++score.overall.observed, ++score.per_material[samples.material[i]].observed;
  }
  for (size_t m = 0; m < 256; ++m) {
    Completeness& c = score.per_material[m];
    c.within.assign(thresholds, 0);
    if (c.observed == 0 || hits[m].empty()) continue;
    for (size_t t = 0; t < thresholds; ++t) c.within[t] = double(hits[m][t]) / c.observed;
  }
  // Accuracy: each map point's distance to the plane of the triangle of its nearest sample.
  if (!samples.points.empty() && !map_points.empty()) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(Cloud(samples.points));
    std::vector<int> index(1);
    std::vector<float> d2(1);
    std::vector<double> all;
    std::array<std::vector<double>, kDepthSources> by_source;
    for (const Surfel& s : map) {
      const Eigen::Vector3f& p = s.position;
      if (tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, d2) < 1) continue;
      const auto& t = mesh.faces[samples.triangle[index[0]]];
      const Eigen::Vector3f a = mesh.vertices[t[0]];
      const Eigen::Vector3f n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
      const double plane = n.norm() > 0 ? std::abs(n.normalized().dot(p - a)) : std::sqrt(d2[0]);
      const double d = std::min<double>(plane, std::sqrt(d2[0]));
      all.push_back(d);
      by_source[std::min<size_t>(s.source, kDepthSources - 1)].push_back(d);
    }
    score.accuracy_median_m = Quantile(all, 0.5);
    score.accuracy_p90_m = Quantile(all, 0.9);
    for (size_t k = 0; k < kDepthSources; ++k) {
      score.source_points[k] = static_cast<long>(by_source[k].size());
      score.source_median_m[k] = Quantile(by_source[k], 0.5);
      score.source_p90_m[k] = Quantile(by_source[k], 0.9);
    }
  }
  return score;
}

TriangleMesh ReadTriangleMeshPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, IsRegularFile(path) ? "cannot open for reading" : "file not found");
  std::string line, format;
  long vertices = -1, faces = -1;
  std::vector<std::pair<std::string, std::string>> vertex_props;  // type, name
  std::string element;
  std::getline(in, line);
  if (line != "ply") throw InputError(path, "not a PLY file");
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream w(line);
    std::string key;
    w >> key;
    if (key == "format") {
      w >> format;
    } else if (key == "element") {
      w >> element;
      if (element == "vertex")
        w >> vertices;
      else if (element == "face")
        w >> faces;
    } else if (key == "property" && element == "vertex") {
      std::string type, name;
      w >> type >> name;
      if (type != "float" && type != "uchar")
        throw InputError(path, "vertex properties must be float or uchar");
      vertex_props.push_back({type, name});
    } else if (key == "property" && element == "face") {
      std::string list, count_type, index_type;
      w >> list >> count_type >> index_type;
      if (list != "list" || count_type != "uchar" || (index_type != "int" && index_type != "uint"))
        throw InputError(path, "faces must be 'property list uchar int vertex_indices'");
    } else if (key == "end_header") {
      break;
    }
  }
  if (vertices < 0 || faces < 0) throw InputError(path, "needs vertex and face elements");
  if (format != "binary_little_endian") throw InputError(path, "only binary_little_endian meshes");
  TriangleMesh mesh;
  mesh.vertices.resize(vertices);
  mesh.material.resize(vertices, 0);
  for (long i = 0; i < vertices; ++i) {
    for (const auto& [type, name] : vertex_props) {
      if (type == "float") {
        float v;
        in.read(reinterpret_cast<char*>(&v), 4);
        if (name == "x") mesh.vertices[i].x() = v;
        if (name == "y") mesh.vertices[i].y() = v;
        if (name == "z") mesh.vertices[i].z() = v;
      } else {
        const int c = in.get();
        if (name == "material") mesh.material[i] = static_cast<uint8_t>(c);
      }
    }
  }
  for (long f = 0; f < faces && in; ++f) {
    const int n = in.get();
    std::vector<int32_t> idx(std::max(n, 0));
    in.read(reinterpret_cast<char*>(idx.data()), 4 * idx.size());
    for (int k = 1; k + 1 < n; ++k) mesh.faces.push_back({idx[0], idx[k], idx[k + 1]});
  }
  if (!in) throw InputError(path, "truncated mesh data");
  for (const auto& t : mesh.faces)
    for (int v : t)
      if (v < 0 || v >= vertices) throw InputError(path, "face refers to a missing vertex");
  return mesh;
}

}  // namespace gf
