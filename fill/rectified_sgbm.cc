#include "fill/rectified_sgbm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

cv::Mat ToCv(const Eigen::Matrix3d& m) {
  cv::Mat out(3, 3, CV_64F);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.at<double>(i, j) = m(i, j);
  return out;
}

// cv::stereoRectify of `first` and `second`; second_from_first maps first-camera points into the
// second camera (OpenCV's R, T). Returns the signed shift of the second camera's projection
// (-f * baseline when `first` is the left camera).
double Rectify(const Camera& camera, const SE3& second_from_first, double alpha,
               SgbmRectification* out) {
  cv::Mat t(3, 1, CV_64F);
  for (int i = 0; i < 3; ++i) t.at<double>(i) = second_from_first.translation()[i];
  const cv::Size size(camera.width, camera.height);
  cv::Mat q;
  cv::stereoRectify(camera.CvK(), camera.CvDistortion(), camera.CvK(), camera.CvDistortion(), size,
                    ToCv(second_from_first.RotationMatrix()), t, out->r_left, out->r_right,
                    out->p_left, out->p_right, q, cv::CALIB_ZERO_DISPARITY, alpha, size);
  out->vertical = std::abs(out->p_right.at<double>(1, 3)) > std::abs(out->p_right.at<double>(0, 3));
  return out->vertical ? out->p_right.at<double>(1, 3) : out->p_right.at<double>(0, 3);
}

// Scales a rectified projection's focal length by `s` about the pixel `fixed` (the view direction
// there stays at that pixel), and the baseline term with it.
void ScaleProjection(double s, const Eigen::Vector2d& fixed, cv::Mat* p) {
  for (int row = 0; row < 2; ++row) {
    p->at<double>(row, row) *= s;
    p->at<double>(row, 2) = fixed[row] + s * (p->at<double>(row, 2) - fixed[row]);
    p->at<double>(row, 3) *= s;
  }
}

Eigen::Vector2d Centre(const cv::Size& size) {
  return {0.5 * (size.width - 1), 0.5 * (size.height - 1)};
}

// The largest squared radius, in undistorted normalised coordinates, of the camera's image
// border: rays beyond it are outside the lens's field of view (where a polynomial distortion
// model folds back into the image and would sample it twice).
double FieldOfViewRadius2(const Camera& camera) {
  double r2 = 0;
  auto at = [&](double x, double y) {
    r2 = std::max(r2, camera.UndistortPixel({x, y}).squaredNorm());
  };
  for (int x = 0; x < camera.width; x += 8) {
    at(x, 0);
    at(x, camera.height - 1);
  }
  for (int y = 0; y < camera.height; y += 8) {
    at(0, y);
    at(camera.width - 1, y);
  }
  at(camera.width - 1, camera.height - 1);
  return r2;
}

// Which pixels of the (untransposed) rectified image, sampled every `step` pixels, show the scene:
// their ray is in front of the camera, inside its field of view and lands in its image.
cv::Mat ValidGrid(const Camera& camera, const cv::Mat& r, const cv::Mat& p, const cv::Size& size,
                  int step, double fov_r2) {
  Eigen::Matrix3d cam_from_rect;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) cam_from_rect(i, j) = r.at<double>(j, i);
  const double f = p.at<double>(0, 0), cx = p.at<double>(0, 2), cy = p.at<double>(1, 2);
  cv::Mat grid((size.height + step - 1) / step, (size.width + step - 1) / step, CV_8UC1);
  for (int j = 0; j < grid.rows; ++j)
    for (int i = 0; i < grid.cols; ++i) {
      const Eigen::Vector3d ray =
          cam_from_rect * Eigen::Vector3d((i * step - cx) / f, (j * step - cy) / f, 1.0);
      bool valid = ray.z() > 0 && (ray.head<2>() / ray.z()).squaredNorm() <= fov_r2;
      valid = valid && camera.InImage(camera.ProjectDistorted(ray));
      grid.at<uint8_t>(j, i) = valid ? 255 : 0;
    }
  return grid;
}

}  // namespace

bool SgbmOptions::Check(std::string* message) const {
  // OpenCV's SGBM aborts the process on a disparity range wider than the image (DESIGN.md).
  FieldCheck c(message);
  c.In("num_disparities", num_disparities, 16, kMaxImageSidePx, kLargerThanAnyImage)
      .Require(num_disparities % 16 == 0, "num_disparities must be a multiple of 16")
      .In("block_size", block_size, 1, kMaxImageSidePx, kLargerThanAnyImage)
      .Require(block_size % 2 == 1, "block_size must be odd")
      .In("rectify_alpha", rectify_alpha, -1, 1, "is beyond cv::stereoRectify's alpha (-1 to 1)")
      // A crop magnified more than an image's side would be smaller than one camera pixel.
      .In("max_zoom", max_zoom, 0, kMaxImageSidePx, "magnifies less than a pixel to an image")
      .Require(max_zoom == 0 || max_zoom >= 0.25, "max_zoom: 0 (none) or at least 0.25")
      .In("min_valid_fraction", min_valid_fraction, 0, 1, kMoreThanOne)
      .In("uniqueness_ratio", uniqueness_ratio, 0, 100, "is more than 100 percent")
      .In("speckle_window", speckle_window, 0, kMaxImagePixels, kMoreThanAnImagesPixels)
      .In("speckle_range", speckle_range, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("max_lr_difference_px", max_lr_difference_px, 0, kMaxImageSidePx, kLargerThanAnyImage);
  return c.ok();
}

bool SgbmParametersFit(int width, int height, int min_disparity, int num_disparities,
                       int block_size) {
  return min_disparity >= 0 && num_disparities >= 16 && num_disparities % 16 == 0 &&
         block_size >= 1 && block_size % 2 == 1 && block_size < std::min(width, height) &&
         2 * (static_cast<long>(min_disparity) + num_disparities) <= width;
}

SgbmRectification RectifyForSgbm(const Camera& camera, const SE3& key1_from_key2, double near_m,
                                 double far_m, const SgbmOptions& options) {
  GF_CHECK(near_m > 0 && far_m > near_m, "need 0 < near_m < far_m");
  SgbmRectification r;
  // SGBM's reference image is the left camera: keyframe 1 when the rectified shift of keyframe 2
  // is negative, else the pair is taken the other way round.
  double shift = Rectify(camera, key1_from_key2.Inverse(), options.rectify_alpha, &r);
  if (shift >= 0) {
    r.swapped = true;
    shift = Rectify(camera, key1_from_key2, options.rectify_alpha, &r);
  }
  r.size = cv::Size(camera.width, camera.height);
  int width = r.vertical ? camera.height : camera.width;
  int height = r.vertical ? camera.width : camera.height;
  // The search covers the depth range (a pixel's depth in the rectified camera differs from
  // keyframe 1's by the rectifying rotation; the caller's range has a margin for that).
  auto search = [&](double fb) {
    r.min_disparity = std::max(0, static_cast<int>(std::floor(fb / far_m)) - 1);
    const int wanted = static_cast<int>(std::ceil(fb / near_m)) + 1 - r.min_disparity;
    r.num_disparities = std::max(16, (wanted + 15) / 16 * 16);
    return r.num_disparities <= options.num_disparities &&
           SgbmParametersFit(width, height, r.min_disparity, r.num_disparities, options.block_size);
  };
  const double fb = -shift;
  double scale = 1.0;
  char text[200];
  // Reduce the focal length in 5% steps until the search fits (a few steps for the crop's usual
  // 1.2-1.9x, about 75 for a 41x one); below a thousandth nothing of the image is left.
  while (fb > 0 && !search(scale * fb) && scale > 1e-3) scale *= 0.95;
  if (!(fb > 0) || !search(scale * fb)) {
    std::snprintf(text, sizeof(text),
                  "depths %.2f-%.2f m need disparities %d-%d (at most %d, ending by %d px)", near_m,
                  far_m, r.min_disparity, r.min_disparity + r.num_disparities,
                  options.num_disparities, width / 2);
    r.refusal = "disparity_range";
    r.problem = text;
    return r;
  }
  if (scale < 1.0) {
    r.rescaled = true;
    ScaleProjection(scale, Centre(r.size), &r.p_left);
    ScaleProjection(scale, Centre(r.size), &r.p_right);
  }
  r.fb = scale * fb;
  // Magnified past max_zoom, the same field of view goes onto a smaller image (a smaller search),
  // unless the search's rounding to 16 disparities does not fit that image.
  const double zoom = r.p_left.at<double>(0, 0) / camera.fx;
  if (options.max_zoom > 0 && zoom > options.max_zoom) {
    SgbmRectification full = r;  // the projections are scaled in place: keep copies
    full.p_left = r.p_left.clone();
    full.p_right = r.p_right.clone();
    const double s = options.max_zoom / zoom;
    r.size = cv::Size(static_cast<int>(std::lround(s * camera.width)),
                      static_cast<int>(std::lround(s * camera.height)));
    const Eigen::Vector2d corner(-0.5, -0.5);  // the images' outer edges stay the views' edges
    ScaleProjection(s, corner, &r.p_left);
    ScaleProjection(s, corner, &r.p_right);
    r.fb *= s;
    width = r.vertical ? r.size.height : r.size.width;
    height = r.vertical ? r.size.width : r.size.height;
    if (!search(r.fb)) r = full;
  }
  r.zoom = r.p_left.at<double>(0, 0) / camera.fx;
  const double fov_r2 = FieldOfViewRadius2(camera);
  const cv::Mat valid = ValidGrid(camera, r.r_left, r.p_left, r.size, 8, fov_r2) &
                        ValidGrid(camera, r.r_right, r.p_right, r.size, 8, fov_r2);
  r.valid_fraction = static_cast<double>(cv::countNonZero(valid)) / valid.total();
  if (r.valid_fraction < options.min_valid_fraction) {
    std::snprintf(text, sizeof(text), "the rectified views share %.0f%% of the image (min %.0f%%)",
                  100 * r.valid_fraction, 100 * options.min_valid_fraction);
    r.refusal = "valid_region";
    r.problem = text;
    return r;
  }
  r.usable = true;
  return r;
}

std::string SgbmRectification::BriefReport() const {
  char buffer[300];
  std::snprintf(buffer, sizeof(buffer),
                "%s%s rectification: zoom %.2f%s on %dx%d, valid %.0f%%, f*b %.1f px m, "
                "disparities %d+%d%s%s",
                vertical ? "vertical" : "horizontal", swapped ? " swapped" : "", zoom,
                rescaled ? " (reduced to fit the search)" : "", size.width, size.height,
                100 * valid_fraction, fb,
                min_disparity, num_disparities, usable ? "" : ": refused, ", problem.c_str());
  return buffer;
}

RectifiedImages RectifyImages(const SgbmRectification& rect, const RgbdFrame& key1,
                              const RgbdFrame& key2, const Camera& camera) {
  GF_CHECK(!rect.r_left.empty(), "the pair was not rectified");
  const cv::Size size = rect.size;
  const double fov_r2 = FieldOfViewRadius2(camera);
  auto remap = [&](const cv::Mat& color, const cv::Mat& r, const cv::Mat& p, cv::Mat* gray_rect,
                   cv::Mat* valid) {
    cv::Mat map, map_fraction, gray;
    cv::initUndistortRectifyMap(camera.CvK(), camera.CvDistortion(), r, p, size, CV_16SC2, map,
                                map_fraction);
    cv::cvtColor(color, gray, cv::COLOR_BGR2GRAY);
    cv::remap(gray, *gray_rect, map, map_fraction, cv::INTER_LINEAR);
    const int step = 4;
    cv::resize(ValidGrid(camera, r, p, size, step, fov_r2), *valid, {}, step, step,
               cv::INTER_NEAREST);
    *valid = (*valid)(cv::Rect(0, 0, size.width, size.height)).clone();
    if (rect.vertical) {  // make epipolar lines horizontal
      // Two destinations: one reused for both would share its buffer with *gray_rect after the
      // first assignment, and the second transpose would overwrite the image with the mask.
      cv::Mat gray_t, valid_t;
      cv::transpose(*gray_rect, gray_t);
      cv::transpose(*valid, valid_t);
      *gray_rect = gray_t;
      *valid = valid_t;
    }
  };
  RectifiedImages out;
  remap(rect.swapped ? key2.color : key1.color, rect.r_left, rect.p_left, &out.left,
        &out.valid_left);
  remap(rect.swapped ? key1.color : key2.color, rect.r_right, rect.p_right, &out.right,
        &out.valid_right);
  return out;
}

std::vector<Eigen::Vector3d> SgbmPoints(const SgbmRectification& rect, const RgbdFrame& key1,
                                        const RgbdFrame& key2, const Camera& camera,
                                        const SgbmOptions& options) {
  GF_CHECK(rect.usable, "SGBM on a refused rectification: " + rect.BriefReport());
  const RectifiedImages images = RectifyImages(rect, key1, key2, camera);
  const int bs = options.block_size;
  // Never call SGBM with a search it cannot survive (RectifyForSgbm refuses those pairs).
  GF_CHECK(SgbmParametersFit(images.left.cols, images.left.rows, rect.min_disparity,
                             rect.num_disparities, bs),
           "SGBM search does not fit the rectified image: " + rect.BriefReport());
  // A pixel counts as valid when its whole block is (beyond the image's own border SGBM pads).
  const cv::Mat block = cv::Mat::ones(bs, bs, CV_8UC1);
  cv::Mat valid1, valid2;
  cv::erode(images.valid_left, valid1, block);
  cv::erode(images.valid_right, valid2, block);
  // SGBM's own left-right check (disp12MaxDiff) computes the right view's disparities from the
  // same cost volume and drops pixels where the two disagree.
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
      rect.min_disparity, rect.num_disparities, bs, 8 * bs * bs, 32 * bs * bs,
      static_cast<int>(std::lround(options.max_lr_difference_px)), 63, options.uniqueness_ratio,
      options.speckle_window, options.speckle_range, cv::StereoSGBM::MODE_SGBM_3WAY);
  cv::Mat raw;  // CV_16S, 4 fractional bits; invalid pixels are below min_disparity
  sgbm->compute(images.left, images.right, raw);
  const double f = rect.p_left.at<double>(0, 0), rcx = rect.p_left.at<double>(0, 2),
               rcy = rect.p_left.at<double>(1, 2);
  Eigen::Matrix3d left_from_rect;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) left_from_rect(i, j) = rect.r_left.at<double>(j, i);
  const int16_t lowest = static_cast<int16_t>(std::max(1, 16 * rect.min_disparity));
  std::vector<Eigen::Vector3d> points;
  points.reserve(static_cast<size_t>(raw.total()) / 2);
  for (int row = 0; row < raw.rows; ++row) {
    const int16_t* d = raw.ptr<int16_t>(row);
    const uint8_t* v1 = valid1.ptr<uint8_t>(row);
    const uint8_t* v2 = valid2.ptr<uint8_t>(row);
    for (int col = 0; col < raw.cols; ++col) {
      if (d[col] < lowest || !v1[col]) continue;
      const int matched = col - (d[col] + 8) / 16;  // the right view's pixel
      if (matched < 0 || !v2[matched]) continue;
      const double z = 16.0 * rect.fb / d[col];
      const int u = rect.vertical ? row : col, v = rect.vertical ? col : row;  // rectified pixel
      points.push_back(left_from_rect * Eigen::Vector3d((u - rcx) * z / f, (v - rcy) * z / f, z));
    }
  }
  return points;
}

}  // namespace gf
