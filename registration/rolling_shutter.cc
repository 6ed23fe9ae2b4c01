#include "registration/rolling_shutter.h"

#include <cmath>
#include <limits>

#include "acquisition/errors.h"

namespace gf {

RollingShutter::RollingShutter(const Camera& camera, double readout_s, ReadoutOrder order)
    : camera_(camera), rays_(camera), readout_s_(readout_s), order_(order) {
  GF_CHECK(readout_s >= 0, "rolling shutter: readout time must be >= 0");
}

cv::Mat RollingShutter::DepthAtLastRow(const cv::Mat& depth,
                                       const SE3::Tangent& twist_per_s) const {
  GF_CHECK(depth.type() == CV_32FC1 && depth.cols == camera_.width && depth.rows == camera_.height,
           "rolling shutter: CV_32F depth of the camera's size");
  const Eigen::Vector3d v = twist_per_s.head<3>(), w = twist_per_s.tail<3>();
  cv::Mat moved_z(depth.size(), CV_32FC1, cv::Scalar(0));  // each pixel's own point, moved
  cv::Mat out(depth.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  // The time of pixel (x, y) relative to the stamp: its line's share of the readout, minus 1.
  auto line_time = [&](int x, int y) {
    const double rows = depth.rows, cols = depth.cols, readout_s = readout_s_;
    switch (order_) {
      case ReadoutOrder::kBottomToTop:
        return ((rows - y - 0.5) / rows - 1.0) * readout_s;
      case ReadoutOrder::kLeftToRight:
        return ((x + 0.5) / cols - 1.0) * readout_s;
      case ReadoutOrder::kRightToLeft:
        return ((cols - x - 0.5) / cols - 1.0) * readout_s;
      default:
        return ((y + 0.5) / rows - 1.0) * readout_s;
    }
  };
  for (int y = 0; y < depth.rows; ++y) {
    const float* d = depth.ptr<float>(y);
    float* own = moved_z.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x) {
      if (!(d[x] > 0)) continue;
      const double dt = line_time(x, y);
      const Eigen::Vector2d ray = rays_.Ray(x, y);
      const Eigen::Vector3d p(ray.x() * d[x], ray.y() * d[x], d[x]);
      const Eigen::Vector3d q = p + (w.cross(p) + v) * dt;
      if (!(q.z() > 0)) continue;
      own[x] = static_cast<float>(q.z());
      const Eigen::Vector2d uv = camera_.ProjectDistorted(q);
      if (!(uv.x() > -0.5 && uv.y() > -0.5 && uv.x() < depth.cols - 0.5 &&
            uv.y() < depth.rows - 0.5))
        continue;  // left the image (or not a number)
      const int u = static_cast<int>(std::lround(uv.x())),
                r = static_cast<int>(std::lround(uv.y()));
      float& target = out.at<float>(r, u);
      target = std::min(target, own[x]);
    }
  }
  for (int y = 0; y < depth.rows; ++y) {
    float* o = out.ptr<float>(y);
    const float* own = moved_z.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x)
      if (std::isinf(o[x])) o[x] = own[x];  // a crack keeps its own point; no point: 0
  }
  return out;
}

}  // namespace gf
