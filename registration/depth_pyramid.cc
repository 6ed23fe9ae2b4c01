#include "registration/depth_pyramid.h"

#include <cmath>
#include <limits>

#include "acquisition/errors.h"

namespace gf {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat HalveDepth(const cv::Mat& depth) {
  cv::Mat out(depth.rows / 2, depth.cols / 2, CV_32FC1);
  for (int y = 0; y < out.rows; ++y) {
    const float* r0 = depth.ptr<float>(2 * y);
    const float* r1 = depth.ptr<float>(2 * y + 1);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      const float c = r0[2 * x];
      float sum = 0.f;
      int n = 0;
      for (float v : {r0[2 * x], r0[2 * x + 1], r1[2 * x], r1[2 * x + 1]}) {
        if (v > 0 && (c <= 0 || std::abs(v - c) < 0.03f)) {
          sum += v;
          ++n;
        }
      }
      o[x] = n ? sum / n : 0.f;
    }
  }
  return out;
}

}  // namespace

DepthPyramid BuildDepthPyramid(const cv::Mat& depth_m, const Camera& camera, int levels) {
  GF_CHECK(depth_m.type() == CV_32FC1 && levels >= 1, "need CV_32F depth and levels >= 1");
  GF_CHECK(depth_m.cols == camera.width && depth_m.rows == camera.height, "depth/camera size");
  DepthPyramid p;
  cv::Mat depth = depth_m;
  Camera cam = camera;
  for (int level = 0; level < levels; ++level) {
    if (level > 0) {
      depth = HalveDepth(depth);
      cam = cam.Scaled(0.5);
      cam.width = depth.cols;
      cam.height = depth.rows;
    }
    cv::Mat vertices(depth.size(), CV_32FC3, cv::Scalar::all(kNaN));
    cv::Mat normals(depth.size(), CV_32FC3, cv::Scalar::all(kNaN));
    for (int y = 0; y < depth.rows; ++y) {
      const float* d = depth.ptr<float>(y);
      cv::Vec3f* v = vertices.ptr<cv::Vec3f>(y);
      for (int x = 0; x < depth.cols; ++x) {
        if (!(d[x] > 0)) continue;
        v[x] = cv::Vec3f(static_cast<float>((x - cam.cx) / cam.fx * d[x]),
                         static_cast<float>((y - cam.cy) / cam.fy * d[x]), d[x]);
      }
    }
    // Normals from central differences; rejected across depth discontinuities.
    for (int y = 1; y + 1 < depth.rows; ++y) {
      for (int x = 1; x + 1 < depth.cols; ++x) {
        const cv::Vec3f& c = vertices.at<cv::Vec3f>(y, x);
        const cv::Vec3f& l = vertices.at<cv::Vec3f>(y, x - 1);
        const cv::Vec3f& r = vertices.at<cv::Vec3f>(y, x + 1);
        const cv::Vec3f& u = vertices.at<cv::Vec3f>(y - 1, x);
        const cv::Vec3f& b = vertices.at<cv::Vec3f>(y + 1, x);
        if (std::isnan(c[2]) || std::isnan(l[2]) || std::isnan(r[2]) || std::isnan(u[2]) ||
            std::isnan(b[2]))
          continue;
        const float jump = 0.05f * c[2];
        if (std::abs(l[2] - r[2]) > 2 * jump || std::abs(u[2] - b[2]) > 2 * jump) continue;
        cv::Vec3f n = (r - l).cross(b - u);
        const float norm = static_cast<float>(cv::norm(n));
        if (norm <= 0) continue;
        n /= norm;
        if (n.dot(c) > 0) n = -n;  // face the camera
        normals.at<cv::Vec3f>(y, x) = n;
      }
    }
    p.cameras.push_back(cam);
    p.depth.push_back(depth);
    p.vertices.push_back(vertices);
    p.normals.push_back(normals);
  }
  return p;
}

}  // namespace gf
