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

cv::Mat GrayFloat(const cv::Mat& bgr) {
  cv::Mat gray, f;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  gray.convertTo(f, CV_32F);
  return f;
}

struct ViewData {
  cv::Mat gray_cover;        // CV_32FC2: undistorted grey level, 1 where the image has content
  Eigen::Matrix3d rotation;  // view_from_key1
  Eigen::Vector3d translation;
};

// Cost volume entries: 100 * (1 - mean NCC) in [0, 200]; textureless_cost where keyframe 1's
// window is flat or no view sees it (neutral: aggregation then carries the neighbours' evidence).

// One path of semi-global aggregation (Hirschmueller 2008) over cost[rows][cols][planes], added
// into sum: L(p, d) = C(p, d) + min(L(q, d), L(q, d +- 1) + p1, min_k L(q, k) + p2) - min_k L(q, k)
// with q the predecessor of p along (dx, dy). Rows are visited in the path's vertical direction,
// so a predecessor is either earlier in the same row (dy = 0) or in the previous row.
void AggregatePath(const std::vector<uint8_t>& cost, int rows, int cols, int planes, int dx, int dy,
                   int p1, int p2, std::vector<uint16_t>* sum) {
  // Each pixel's L row is padded with one large entry on either side, so that the d - 1 and
  // d + 1 neighbours need no bounds checks (and the loop vectorises).
  const size_t stride = static_cast<size_t>(planes) + 2;
  constexpr uint16_t kPad = 0x3fff;
  std::vector<uint16_t> previous(cols * stride, kPad), current(cols * stride, kPad);
  std::vector<uint16_t> previous_min(cols), current_min(cols);
  for (int i = 0; i < rows; ++i) {
    const int y = dy >= 0 ? i : rows - 1 - i;
    for (int j = 0; j < cols; ++j) {
      const int x = dx >= 0 ? j : cols - 1 - j;
      const uint8_t* __restrict c = &cost[(static_cast<size_t>(y) * cols + x) * planes];
      uint16_t* __restrict l = &current[x * stride + 1];
      uint16_t* __restrict s = &(*sum)[(static_cast<size_t>(y) * cols + x) * planes];
      const int px = x - dx, py = y - dy;
      uint16_t lowest = kPad;
      if (px < 0 || px >= cols || py < 0 || py >= rows) {
        for (int d = 0; d < planes; ++d) l[d] = c[d];
      } else {
        const uint16_t* __restrict q =
            dy == 0 ? &current[px * stride + 1] : &previous[px * stride + 1];
        const uint16_t q_min = dy == 0 ? current_min[px] : previous_min[px];
        const uint16_t jump = static_cast<uint16_t>(q_min + p2), small = static_cast<uint16_t>(p1);
        for (int d = 0; d < planes; ++d) {
          uint16_t v = std::min(q[d], jump);
          v = std::min(v, static_cast<uint16_t>(std::min(q[d - 1], q[d + 1]) + small));
          l[d] = static_cast<uint16_t>(c[d] + v - q_min);
        }
      }
      for (int d = 0; d < planes; ++d) {
        lowest = std::min(lowest, l[d]);
        s[d] = static_cast<uint16_t>(s[d] + l[d]);
      }
      current_min[x] = lowest;
    }
    std::swap(previous, current);
    std::swap(previous_min, current_min);
  }
}

}  // namespace

bool PlaneSweepOptions::Check(std::string* message) const {
  if (window_px < 3 || window_px % 2 == 0 || max_planes < 3 || max_planes > 250 ||
      !(max_step_px > 0) || !(min_ncc > -1 && min_ncc < 1) ||
      !(min_uniqueness >= 0 && min_uniqueness < 1) || !(min_parallax_px >= 0) ||
      !(min_texture >= 0) || !(min_window_inside > 0 && min_window_inside <= 1) ||
      smooth_small < 0 || smooth_large < smooth_small || smooth_large > 1000 ||
      textureless_cost < 0 || textureless_cost > 200 || downscale < 1 || downscale > 4) {
    if (message)
      *message =
          "plane sweep: odd window >= 3, 3..250 planes, thresholds in range, 0 <= smooth_small <= "
          "smooth_large <= 1000, textureless_cost in [0, 200], downscale 1..4";
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
  GF_CHECK(mask.cols == camera.width && mask.rows == camera.height, "images: the camera's size");
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
  if (distorted) camera.UndistortionMaps(&map_x, &map_y);
  auto undistort = [&](const cv::Mat& image, int interpolation) {
    if (!distorted) return image;
    cv::Mat out;
    cv::remap(image, out, map_x, map_y, interpolation, cv::BORDER_CONSTANT, cv::Scalar(0));
    return out;
  };
  // Box filters keep running sums, so a NaN would poison whole rows: pixels outside an image are
  // 0 and tracked by a coverage image instead. Correlation windows are weighted by keyframe 1's
  // coverage, so windows that cross its image border use the part inside. The sweep runs on
  // images shrunk by `downscale` (area averaging) with the camera matrix scaled to match.
  const double scale = 1.0 / options.downscale;
  const Camera work_camera = camera.Scaled(scale);  // the working images' pinhole camera
  const cv::Size work(work_camera.width, work_camera.height);
  const cv::Mat ones(size, CV_32F, cv::Scalar(1.f));
  const cv::Mat cover_full = undistort(ones, cv::INTER_NEAREST);
  cv::Mat cover1;
  cv::resize(cover_full, cover1, work, 0, 0, cv::INTER_AREA);
  // Grey levels at working size: the mean over the covered part of each cell, 0 outside.
  auto shrink_gray = [&](const cv::Mat& bgr) {
    cv::Mat gray = undistort(GrayFloat(bgr), cv::INTER_LINEAR).mul(cover_full), out;
    cv::resize(gray, out, work, 0, 0, cv::INTER_AREA);
    cv::divide(out, cv::max(cover1, 1e-6), out);
    return out;
  };
  cv::threshold(cover1, cover1, 0.99, 1.0, cv::THRESH_BINARY);
  const cv::Mat gray1 = shrink_gray(key1.color).mul(cover1);
  cv::Mat region_full = undistort(mask, cv::INTER_NEAREST), region;
  region_full.convertTo(region_full, CV_32F);
  cv::resize(region_full, region, work, 0, 0, cv::INTER_AREA);
  region = region > 0;  // a working pixel is wanted when any of its pixels is
  cv::dilate(region, region, cv::Mat());
  std::vector<ViewData> data;
  double max_baseline = 0;
  for (const SweepView& v : views) {
    GF_CHECK(v.frame != nullptr && v.frame->color.type() == CV_8UC3, "views need BGR colour");
    const SE3 view_from_key1 = v.key1_from_view.Inverse();
    cv::Mat gray_cover;
    cv::merge(std::vector<cv::Mat>{shrink_gray(v.frame->color), cover1}, gray_cover);
    data.push_back({gray_cover, view_from_key1.RotationMatrix(), view_from_key1.translation()});
    max_baseline = std::max(max_baseline, view_from_key1.TranslationNorm());
  }
  const Eigen::Matrix3d k = work_camera.K(), k_inv = k.inverse();

  // Work on the bounding box of the region, widened by the window.
  const int half = options.window_px / 2;
  cv::Rect roi = cv::boundingRect(region);
  roi.x -= half + 1;
  roi.y -= half + 1;
  roi.width += 2 * half + 2;
  roi.height += 2 * half + 2;
  roi &= cv::Rect(0, 0, work.width, work.height);
  const cv::Size box(options.window_px, options.window_px);
  const cv::Mat i_roi = gray1(roi), c_roi = cover1(roi);
  cv::Mat n1, mean_i, var_i;  // window means weighted by keyframe 1's coverage
  cv::boxFilter(c_roi, n1, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
  cv::boxFilter(i_roi, mean_i, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
  cv::boxFilter(i_roi.mul(i_roi), var_i, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
  cv::max(n1, 1e-6, n1);
  cv::divide(mean_i, n1, mean_i);
  cv::divide(var_i, n1, var_i);
  var_i -= mean_i.mul(mean_i);
  const double min_var = options.min_texture * options.min_texture;

  // Planes evenly spaced in inverse depth, close enough that no pixel jumps more than max_step_px.
  const double f = std::max(k(0, 0), k(1, 1));
  const double w_near = 1.0 / min_depth_m, w_far = 1.0 / max_depth_m;
  const double step_needed = options.max_step_px / (1.5 * f * std::max(max_baseline, 1e-6));
  result.planes = std::clamp(static_cast<int>(std::ceil((w_near - w_far) / step_needed)) + 1, 3,
                             options.max_planes);
  const int planes = result.planes;
  const double dw = (w_near - w_far) / (planes - 1);

  const int rows = roi.height, cols = roi.width;
  const size_t pixels = static_cast<size_t>(rows) * cols;
  std::vector<uint8_t> cost(pixels * planes);
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();  // ROI pixel -> full image pixel
  shift(0, 2) = roi.x;
  shift(1, 2) = roi.y;
  cv::Mat sum(rows, cols, CV_32F), count(rows, cols, CV_32F), seen(rows, cols, CV_8U);
  cv::Mat warped, stack(rows, cols, CV_32FC4), means;
  for (int plane = 0; plane < planes; ++plane) {
    const double w = w_far + plane * dw;
    sum.setTo(0.f);
    count.setTo(0.f);
    seen.setTo(0);
    for (const ViewData& v : data) {
      Eigen::Matrix3d h = v.rotation;
      h.col(2) += v.translation * w;  // R + t n^T / z with n = (0, 0, 1)
      const Eigen::Matrix3d key1_to_view = k * h * k_inv * shift;
      cv::Mat homography;
      cv::eigen2cv(key1_to_view, homography);
      cv::warpPerspective(v.gray_cover, warped, homography, roi.size(),
                          cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT,
                          cv::Scalar(0, 0));
      // Window sums of J, J^2, I J and the view's coverage, over keyframe 1's covered pixels.
      for (int y = 0; y < rows; ++y) {
        const cv::Vec2f* jw = warped.ptr<cv::Vec2f>(y);
        const float* iv = i_roi.ptr<float>(y);
        const float* cv1 = c_roi.ptr<float>(y);
        cv::Vec4f* out = stack.ptr<cv::Vec4f>(y);
        for (int x = 0; x < cols; ++x) {
          const float j = jw[x][0] * cv1[x];
          out[x] = cv::Vec4f(j, j * jw[x][0], j * iv[x], jw[x][1] * cv1[x]);
        }
      }
      cv::boxFilter(stack, means, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
      for (int y = 0; y < rows; ++y) {
        const cv::Vec4f* m = means.ptr<cv::Vec4f>(y);
        const float* n = n1.ptr<float>(y);
        const float* mi = mean_i.ptr<float>(y);
        const float* vi = var_i.ptr<float>(y);
        float* s = sum.ptr<float>(y);
        float* c = count.ptr<float>(y);
        uint8_t* sn = seen.ptr<uint8_t>(y);
        for (int x = 0; x < cols; ++x) {
          // The view must cover every pixel of the window that keyframe 1 covers.
          if (n[x] < options.min_window_inside || m[x][3] < n[x] - 1e-3f) continue;
          sn[x] = 1;
          const float inv_n = 1.f / n[x];
          const float mj = m[x][0] * inv_n;
          const float vj = m[x][1] * inv_n - mj * mj;
          if (!(vj > min_var) || !(vi[x] > min_var)) continue;
          s[x] += (m[x][2] * inv_n - mi[x] * mj) / std::sqrt(vi[x] * vj);
          c[x] += 1.f;
        }
      }
    }
    for (int y = 0; y < rows; ++y) {
      const float* s = sum.ptr<float>(y);
      const float* c = count.ptr<float>(y);
      const float* vi = var_i.ptr<float>(y);
      const uint8_t* sn = seen.ptr<uint8_t>(y);
      uint8_t* out = &cost[static_cast<size_t>(y) * cols * planes + plane];
      for (int x = 0; x < cols; ++x, out += planes) {
        if (!sn[x] || !(vi[x] > min_var)) {
          *out = static_cast<uint8_t>(options.textureless_cost);
        } else if (c[x] == 0) {
          *out = 100;  // textured here, flat in every view: no match
        } else {
          *out =
              static_cast<uint8_t>(std::clamp(std::lround(100.0 * (1.0 - s[x] / c[x])), 0L, 200L));
        }
      }
    }
  }

  // Aggregation along 8 paths (or none), then the best plane per pixel.
  const bool smooth = options.smooth_large > 0;
  std::vector<uint16_t> total;
  if (smooth) {
    total.assign(pixels * planes, 0);
    for (const auto& [dx, dy] : std::vector<std::pair<int, int>>{
             {1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, 1}, {1, -1}, {-1, -1}})
      AggregatePath(cost, rows, cols, planes, dx, dy, options.smooth_small, options.smooth_large,
                    &total);
  } else {
    total.assign(cost.begin(), cost.end());
  }

  // Accept, refine, and write back into keyframe 1's (distorted) pixel grid.
  cv::Mat depth_u(work, CV_32F, cv::Scalar(0.f)), score_u(work, CV_32F, cv::Scalar(0.f));
  const double min_parallax = options.min_parallax_px * scale;  // working pixels
  for (int y = 0; y < rows; ++y) {
    const uint8_t* r = region.ptr<uint8_t>(y + roi.y) + roi.x;
    const float* vi = var_i.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      if (!r[x]) continue;
      const size_t base = (static_cast<size_t>(y) * cols + x) * planes;
      const uint16_t* t = &total[base];
      const int bk = static_cast<int>(std::min_element(t, t + planes) - t);
      const uint8_t c = cost[base + bk];
      // Flat windows carry no evidence of their own; aggregation would only copy a neighbour's
      // depth into them (across occlusion edges too), so they get none.
      if (!(vi[x] > min_var) || c > 100.0 * (1.0 - options.min_ncc)) continue;
      int others = std::numeric_limits<int>::max();
      for (int d = 0; d < planes; ++d)
        if (std::abs(d - bk) > 1) others = std::min<int>(others, t[d]);
      if (t[bk] > (1.0 - options.min_uniqueness) * others) continue;
      double offset = 0;
      if (bk > 0 && bk + 1 < planes) {
        const double l = t[bk - 1], b = t[bk], rt = t[bk + 1];
        const double denominator = l - 2.0 * b + rt;
        if (denominator > 0) offset = std::clamp(0.5 * (l - rt) / denominator, -0.5, 0.5);
      }
      const double z = 1.0 / (w_far + (bk + offset) * dw);
      // Parallax: how far a 3% depth change moves the pixel in the best-placed view.
      const Eigen::Vector3d ray = k_inv * Eigen::Vector3d(x + roi.x, y + roi.y, 1.0);
      // Only views that see the point count (a pixel no view sees has no depth).
      double parallax = 0;
      for (const ViewData& v : data) {
        const Eigen::Vector3d a = v.rotation * ray * z + v.translation;
        const Eigen::Vector3d b3 = v.rotation * ray * (1.03 * z) + v.translation;
        if (a.z() <= 0 || b3.z() <= 0) continue;
        const Eigen::Vector2d pa = (k * a).hnormalized(), pb = (k * b3).hnormalized();
        if (pa.x() < 0 || pa.y() < 0 || pa.x() > work.width - 1 || pa.y() > work.height - 1)
          continue;
        parallax = std::max(parallax, (pa - pb).norm());
      }
      if (parallax < min_parallax) continue;
      depth_u.at<float>(y + roi.y, x + roi.x) = static_cast<float>(z);
      score_u.at<float>(y + roi.y, x + roi.x) = 1.f - c / 100.f;
    }
  }
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      Eigen::Vector2d u(x, y);  // undistorted pixel, full size
      if (distorted) {
        const Eigen::Vector2d n = camera.UndistortPixel({x, y});
        u = Eigen::Vector2d(camera.fx * n.x() + camera.cx, camera.fy * n.y() + camera.cy);
      }
      const int ux = static_cast<int>(std::lround((u.x() + 0.5) * scale - 0.5)),
                uy = static_cast<int>(std::lround((u.y() + 0.5) * scale - 0.5));
      if (ux < 0 || uy < 0 || ux >= work.width || uy >= work.height) continue;
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
