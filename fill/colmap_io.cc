#include "fill/colmap_io.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

// Data lines of a COLMAP text file (comments and blank lines dropped), with line numbers.
std::vector<std::pair<int, std::string>> DataLines(const std::string& path, bool keep_blank) {
  std::istringstream in(ReadTextFile(path));
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty() && line[0] == '#') continue;
    if (line.find_first_not_of(" \t") == std::string::npos && !keep_blank) continue;
    lines.emplace_back(number, line);
  }
  return lines;
}

}  // namespace

void WriteColmapTextModel(const std::string& sparse_dir, const Camera& camera,
                          const std::vector<ColmapImage>& images) {
  std::error_code ec;
  fs::create_directories(sparse_dir, ec);
  if (ec) throw InputError(sparse_dir, "cannot create folder: " + ec.message());
  char line[512];
  const auto& d = camera.distortion;
  std::snprintf(line, sizeof(line),
                "1 FULL_OPENCV %d %d %.10g %.10g %.10g %.10g %.10g %.10g %.10g %.10g %.10g %.10g %.10g "
                "%.10g\n",
                camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy, d[0], d[1],
                d[2], d[3], d[4], d[5], d[6], d[7]);
  WriteTextFileAtomically((fs::path(sparse_dir) / "cameras.txt").string(),
                          "# Camera list with one line of data per camera:\n"
                          "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
                          "# Number of cameras: 1\n" +
                              std::string(line));
  std::string text =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(images.size()) + ", mean observations per image: 0\n";
  for (const ColmapImage& image : images) {
    const SE3 camera_from_world = image.world_from_camera.Inverse();
    const Eigen::Quaterniond& q = camera_from_world.rotation();
    const Eigen::Vector3d& t = camera_from_world.translation();
    std::snprintf(line, sizeof(line), "%d %.12g %.12g %.12g %.12g %.12g %.12g %.12g %d %s\n\n",
                  image.id, q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z(), image.camera_id,
                  image.name.c_str());
    text += line;
  }
  WriteTextFileAtomically((fs::path(sparse_dir) / "images.txt").string(), text);
  WriteTextFileAtomically((fs::path(sparse_dir) / "points3D.txt").string(),
                          "# 3D point list with one line of data per point:\n"
                          "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, "
                          "POINT2D_IDX)\n"
                          "# Number of points: 0, mean track length: 0\n");
}

std::map<int, Camera> ReadColmapCameras(const std::string& path) {
  std::map<int, Camera> cameras;
  for (const auto& [number, line] : DataLines(path, false)) {
    std::istringstream in(line);
    int id = 0;
    std::string model;
    Camera c;
    std::vector<double> p;
    in >> id >> model >> c.width >> c.height;
    for (double v; in >> v;) p.push_back(v);
    const std::string where = path + ":" + std::to_string(number);
    auto need = [&](size_t n) {
      if (p.size() < n)
        throw InputError(where, model + " needs " + std::to_string(n) + " parameters");
    };
    if (!in.eof() || id <= 0) throw InputError(where, "malformed camera line");
    if (model == "SIMPLE_PINHOLE") {
      need(3);
      c.fx = c.fy = p[0];
      c.cx = p[1];
      c.cy = p[2];
    } else if (model == "PINHOLE" || model == "OPENCV" || model == "FULL_OPENCV") {
      need(model == "PINHOLE" ? 4 : model == "OPENCV" ? 8 : 12);
      c.fx = p[0];
      c.fy = p[1];
      c.cx = p[2];
      c.cy = p[3];
      if (model == "OPENCV") c.distortion = {p[4], p[5], p[6], p[7], 0, 0, 0, 0};
      if (model == "FULL_OPENCV") c.distortion = {p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11]};
    } else {
      throw InputError(where, "unsupported camera model " + model);
    }
    std::string problem;
    if (!c.Check(&problem)) throw InputError(where, problem);
    cameras[id] = c;
  }
  return cameras;
}

std::vector<ColmapImage> ReadColmapImages(const std::string& path) {
  std::vector<ColmapImage> images;
  const auto lines = DataLines(path, true);
  // Pose lines alternate with (possibly empty) 2D point lines.
  for (size_t i = 0; i < lines.size(); i += 2) {
    const auto& [number, line] = lines[i];
    std::istringstream in(line);
    ColmapImage image;
    double qw, qx, qy, qz, tx, ty, tz;
    if (!(in >> image.id >> qw >> qx >> qy >> qz >> tx >> ty >> tz >> image.camera_id >>
          image.name))
      throw InputError(path + ":" + std::to_string(number), "malformed image line");
    const Eigen::Quaterniond q(qw, qx, qy, qz);
    if (std::abs(q.norm() - 1.0) > 1e-3)
      throw InputError(path + ":" + std::to_string(number), "rotation is not a unit quaternion");
    image.world_from_camera = SE3(q.normalized(), Eigen::Vector3d(tx, ty, tz)).Inverse();
    images.push_back(image);
  }
  return images;
}

cv::Mat ReadColmapDepthMap(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open depth map");
  int size[3] = {0, 0, 0};
  for (int& v : size) {
    std::string field;
    if (!std::getline(in, field, '&')) throw InputError(path, "no width&height&channels& header");
    try {
      v = std::stoi(field);
    } catch (const std::exception&) {
      throw InputError(path, "bad header field \"" + field + "\"");
    }
  }
  const int width = size[0], height = size[1], channels = size[2];
  if (width <= 0 || height <= 0 || channels <= 0 || width > 100000 || height > 100000)
    throw InputError(path, "implausible size in header");
  cv::Mat depth(height, width, CV_32FC1);
  in.read(reinterpret_cast<char*>(depth.data), static_cast<std::streamsize>(depth.total() * 4));
  if (in.gcount() != static_cast<std::streamsize>(depth.total() * 4))
    throw InputError(path, "truncated: fewer values than the header's size");
  cv::patchNaNs(depth, 0);
  depth.setTo(0.f, depth < 0);
  return depth;
}

void WriteColmapDepthMap(const std::string& path, const cv::Mat& depth) {
  GF_CHECK(depth.type() == CV_32FC1 && depth.isContinuous(), "depth maps are CV_32FC1");
  WriteFileAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << depth.cols << "&" << depth.rows << "&1&";
    out.write(reinterpret_cast<const char*>(depth.data),
              static_cast<std::streamsize>(depth.total() * 4));
    if (!out) throw InputError(path, "cannot write depth map");
  });
}

}  // namespace gf
