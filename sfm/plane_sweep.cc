#include "sfm/plane_sweep.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "acquisition/errors.h"

namespace gf {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat GrayFloat(const cv::Mat& bgr) {
  cv::Mat gray, f;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  gray.convertTo(f, CV_32F);
  return f;
}

struct ViewData {
  cv::Mat gray;              // undistorted, CV_32F
  cv::Mat cover;             // CV_32F, 1 where the undistorted image has content
  Eigen::Matrix3d rotation;  // view_from_key1
  Eigen::Vector3d translation;
};

}  // namespace

bool PlaneSweepOptions::Check(std::string* message) const {
  if (window_px < 3 || window_px % 2 == 0 || max_planes < 3 || !(max_step_px > 0) ||
      !(min_ncc > -1 && min_ncc < 1) || !(min_ncc_margin >= 0) || !(min_parallax_px >= 0) ||
      !(min_texture >= 0)) {
    if (message) *message = "plane sweep: odd window >= 3, >= 3 planes, thresholds in range";
    return false;
  }
  return true;
}

std::string PlaneSweepResult::BriefReport() const {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "plane sweep: %d planes, %d of %d pixels accepted", planes,
                accepted_pixels, requested_pixels);
  return buffer;
}

PlaneSweepResult SweepDepth(const RgbdFrame& key1, const std::vector<SweepView>& views,
                            const Camera& camera, const cv::Mat& mask, double min_depth_m,
                            double max_depth_m, const PlaneSweepOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(mask.type() == CV_8UC1 && mask.size() == key1.color.size(), "mask: CV_8U, image size");
  GF_CHECK(min_depth_m > 0 && max_depth_m > min_depth_m, "need 0 < min_depth < max_depth");
  PlaneSweepResult result;
  result.depth = cv::Mat::zeros(mask.size(), CV_32FC1);
  result.score = cv::Mat::zeros(mask.size(), CV_32FC1);
  result.requested_pixels = cv::countNonZero(mask);
  if (result.requested_pixels == 0 || views.empty()) return result;

  // Undistort everything once; from here on the camera is the pinhole K.
  const cv::Size size = mask.size();
  const bool distorted = camera.HasDistortion();
  cv::Mat map_x, map_y;
  if (distorted)
    cv::initUndistortRectifyMap(camera.CvK(), camera.CvDistortion(), cv::Mat(), camera.CvK(), size,
                                CV_32FC1, map_x, map_y);
  auto undistort = [&](const cv::Mat& image, int interpolation) {
    if (!distorted) return image;
    cv::Mat out;
    cv::remap(image, out, map_x, map_y, interpolation, cv::BORDER_CONSTANT, cv::Scalar(0));
    return out;
  };
  // Box filters keep running sums, so a NaN would poison whole rows: pixels outside an image are
  // 0 and tracked by a coverage image instead (its window mean is 1 where all of it is inside).
  const cv::Mat gray1 = undistort(GrayFloat(key1.color), cv::INTER_LINEAR);
  const cv::Mat ones(size, CV_32F, cv::Scalar(1.f));
  const cv::Mat cover1 = undistort(ones, cv::INTER_NEAREST);
  cv::Mat region = undistort(mask, cv::INTER_NEAREST);
  cv::dilate(region, region, cv::Mat());
  std::vector<ViewData> data;
  double max_baseline = 0;
  for (const SweepView& v : views) {
    GF_CHECK(v.frame != nullptr && v.frame->color.type() == CV_8UC3, "views need BGR colour");
    const SE3 view_from_key1 = v.key1_from_view.Inverse();
    data.push_back({undistort(GrayFloat(v.frame->color), cv::INTER_LINEAR), cover1,
                    view_from_key1.RotationMatrix(), view_from_key1.translation()});
    max_baseline = std::max(max_baseline, view_from_key1.TranslationNorm());
  }

  // Work on the bounding box of the region, widened by the window.
  const int half = options.window_px / 2;
  cv::Rect roi = cv::boundingRect(region);
  roi.x -= half + 1;
  roi.y -= half + 1;
  roi.width += 2 * half + 2;
  roi.height += 2 * half + 2;
  roi &= cv::Rect(0, 0, size.width, size.height);
  const cv::Size box(options.window_px, options.window_px);
  const cv::Mat i_roi = gray1(roi);
  cv::Mat mean_i, mean_ii, var_i, inside_i;
  cv::boxFilter(i_roi, mean_i, CV_32F, box);
  cv::boxFilter(i_roi.mul(i_roi), mean_ii, CV_32F, box);
  cv::boxFilter(cover1(roi), inside_i, CV_32F, box);
  var_i = mean_ii - mean_i.mul(mean_i);
  var_i.setTo(0.f, inside_i < 0.999f);  // windows leaving keyframe 1's image are skipped

  // Planes evenly spaced in inverse depth, close enough that no pixel jumps more than max_step_px.
  const double f = std::max(camera.fx, camera.fy);
  const double w_near = 1.0 / min_depth_m, w_far = 1.0 / max_depth_m;
  const double step_needed = options.max_step_px / (1.5 * f * std::max(max_baseline, 1e-6));
  result.planes = std::clamp(static_cast<int>(std::ceil((w_near - w_far) / step_needed)) + 1, 3,
                             options.max_planes);
  const double dw = (w_near - w_far) / (result.planes - 1);

  const int rows = roi.height, cols = roi.width;
  cv::Mat best(rows, cols, CV_32F, cv::Scalar(-2.f)), best_k(rows, cols, CV_32S, cv::Scalar(-1));
  cv::Mat second(rows, cols, CV_32F, cv::Scalar(-2.f)), left(rows, cols, CV_32F, cv::Scalar(kNaN));
  cv::Mat right(rows, cols, CV_32F, cv::Scalar(kNaN)),
      previous(rows, cols, CV_32F, cv::Scalar(kNaN));
  const Eigen::Matrix3d k = camera.K(), k_inv = k.inverse();
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();  // ROI pixel -> full image pixel
  shift(0, 2) = roi.x;
  shift(1, 2) = roi.y;
  const double min_var = options.min_texture * options.min_texture;
  cv::Mat sum(rows, cols, CV_32F), count(rows, cols, CV_32F), warped, mean_j, mean_jj, mean_ij;
  cv::Mat cover, inside;
  for (int plane = 0; plane < result.planes; ++plane) {
    const double w = w_far + plane * dw;
    sum.setTo(0.f);
    count.setTo(0.f);
    for (const ViewData& v : data) {
      Eigen::Matrix3d h = v.rotation;
      h.col(2) += v.translation * w;  // R + t n^T / z with n = (0, 0, 1)
      const Eigen::Matrix3d key1_to_view = k * h * k_inv * shift;
      cv::Mat homography;
      cv::eigen2cv(key1_to_view, homography);
      cv::warpPerspective(v.gray, warped, homography, roi.size(),
                          cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT,
                          cv::Scalar(0));
      cv::warpPerspective(v.cover, cover, homography, roi.size(),
                          cv::INTER_NEAREST | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT,
                          cv::Scalar(0));
      cv::boxFilter(cover, inside, CV_32F, box);
      cv::boxFilter(warped, mean_j, CV_32F, box);
      cv::boxFilter(warped.mul(warped), mean_jj, CV_32F, box);
      cv::boxFilter(warped.mul(i_roi), mean_ij, CV_32F, box);
      for (int y = 0; y < rows; ++y) {
        const float* mi = mean_i.ptr<float>(y);
        const float* vi = var_i.ptr<float>(y);
        const float* mj = mean_j.ptr<float>(y);
        const float* mjj = mean_jj.ptr<float>(y);
        const float* mij = mean_ij.ptr<float>(y);
        const float* in = inside.ptr<float>(y);
        float* s = sum.ptr<float>(y);
        float* c = count.ptr<float>(y);
        for (int x = 0; x < cols; ++x) {
          const float vj = mjj[x] - mj[x] * mj[x];
          if (in[x] < 0.999f || !(vj > min_var) || !(vi[x] > min_var)) continue;
          s[x] += (mij[x] - mi[x] * mj[x]) / std::sqrt(vi[x] * vj);
          c[x] += 1.f;
        }
      }
    }
    for (int y = 0; y < rows; ++y) {
      const uint8_t* r = region.ptr<uint8_t>(y + roi.y) + roi.x;
      const float* s = sum.ptr<float>(y);
      const float* c = count.ptr<float>(y);
      float* b = best.ptr<float>(y);
      int* bk = best_k.ptr<int>(y);
      float* sec = second.ptr<float>(y);
      float* l = left.ptr<float>(y);
      float* rt = right.ptr<float>(y);
      float* prev = previous.ptr<float>(y);
      for (int x = 0; x < cols; ++x) {
        if (!r[x]) continue;
        const float score = c[x] > 0 ? s[x] / c[x] : kNaN;
        if (bk[x] == plane - 1) rt[x] = score;
        if (score > b[x]) {
          if (bk[x] >= 0 && plane - bk[x] > 2) sec[x] = std::max(sec[x], b[x]);
          b[x] = score;
          bk[x] = plane;
          l[x] = prev[x];
          rt[x] = kNaN;
        } else if (plane - bk[x] > 2 && score > sec[x]) {
          sec[x] = score;
        }
        prev[x] = score;
      }
    }
  }

  // Accept, refine, and write back into keyframe 1's (distorted) pixel grid.
  cv::Mat depth_u(size, CV_32F, cv::Scalar(0.f)), score_u(size, CV_32F, cv::Scalar(0.f));
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const int bk = best_k.at<int>(y, x);
      const float b = best.at<float>(y, x);
      if (bk < 0 || !(b >= options.min_ncc) || b - second.at<float>(y, x) < options.min_ncc_margin)
        continue;
      double offset = 0;
      const float l = left.at<float>(y, x), r = right.at<float>(y, x);
      if (!std::isnan(l) && !std::isnan(r)) {
        const double denominator = l - 2.0 * b + r;
        if (denominator < 0) offset = std::clamp(0.5 * (l - r) / denominator, -0.5, 0.5);
      }
      const double z = 1.0 / (w_far + (bk + offset) * dw);
      // Parallax: how far a 3% depth change moves the pixel in the best-placed view.
      const Eigen::Vector3d ray = k_inv * Eigen::Vector3d(x + roi.x, y + roi.y, 1.0);
      double parallax = 0;
      for (const ViewData& v : data) {
        const Eigen::Vector3d a = v.rotation * ray * z + v.translation;
        const Eigen::Vector3d b3 = v.rotation * ray * (1.03 * z) + v.translation;
        if (a.z() <= 0 || b3.z() <= 0) continue;
        const Eigen::Vector2d pa = (k * a).hnormalized(), pb = (k * b3).hnormalized();
        parallax = std::max(parallax, (pa - pb).norm());
      }
      if (parallax < options.min_parallax_px) continue;
      depth_u.at<float>(y + roi.y, x + roi.x) = static_cast<float>(z);
      score_u.at<float>(y + roi.y, x + roi.x) = b;
    }
  }
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      int ux = x, uy = y;
      if (distorted) {
        const Eigen::Vector2d n = camera.UndistortPixel({x, y});
        ux = static_cast<int>(std::lround(camera.fx * n.x() + camera.cx));
        uy = static_cast<int>(std::lround(camera.fy * n.y() + camera.cy));
        if (ux < 0 || uy < 0 || ux >= size.width || uy >= size.height) continue;
      }
      const float z = depth_u.at<float>(uy, ux);
      if (!(z > 0)) continue;
      result.depth.at<float>(y, x) = z;
      result.score.at<float>(y, x) = score_u.at<float>(uy, ux);
      ++result.accepted_pixels;
    }
  }
  return result;
}

}  // namespace gf
