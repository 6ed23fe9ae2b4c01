#include "fill/depth_filters.h"

#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "acquisition/bounds.h"
#include "acquisition/depth.h"
#include "acquisition/stats.h"

namespace gf {

bool DepthStepOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("jump", jump, 0, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .In("far_side_px", far_side_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("near_side_px", near_side_px, 0, kMaxImageSidePx, kLargerThanAnyImage);
  return c.ok();
}

bool SeeThroughOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Above("ratio", ratio, -1, kMaxRelativeDepth, kBeyondAnyDepthRange)
      .In("rim_px", rim_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .In("near_side_px", near_side_px, 0, kMaxImageSidePx, kLargerThanAnyImage);
  return c.ok();
}

cv::Mat WithoutDepthSteps(const cv::Mat& depth, int far_side_px, int near_side_px, double jump) {
  if (far_side_px <= 0 && near_side_px <= 0) return depth.clone();
  auto square = [](int r) {
    return cv::getStructuringElement(cv::MORPH_RECT, {2 * r + 1, 2 * r + 1});
  };
  // A margin of 0 compares each depth with itself, which never drops it.
  cv::Mat farthest, nearest;
  if (near_side_px > 0)
    cv::dilate(depth, farthest, square(near_side_px));
  else
    farthest = depth;
  if (far_side_px > 0) {
    nearest = depth.clone();
    nearest.setTo(std::numeric_limits<float>::max(), depth <= 0.f);
    cv::erode(nearest, nearest, square(far_side_px));
  } else {
    nearest = depth;
  }
  const float up = static_cast<float>(1.0 + jump), down = static_cast<float>(1.0 - jump);
  cv::Mat kept = depth.clone();
  for (int y = 0; y < depth.rows; ++y) {
    float* k = kept.ptr<float>(y);
    const float* f = farthest.ptr<float>(y);
    const float* n = nearest.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x)
      if (f[x] > k[x] * up || n[x] < k[x] * down) k[x] = 0.f;
  }
  return kept;
}

void DropNearSideWithinHoles(const cv::Mat& hole_mask, int near_side_px, double jump,
                             const cv::Mat& where, cv::Mat* depth) {
  if (near_side_px <= 0) return;
  cv::Mat in_holes = depth->clone();
  in_holes.setTo(0.f, hole_mask == 0);
  const cv::Mat kept = WithoutDepthSteps(in_holes, 0, near_side_px, jump);
  cv::Mat dropped = (in_holes > 0.f) & (kept <= 0.f);
  if (!where.empty()) dropped &= where != 0;
  depth->setTo(0.f, dropped);
}

void KeepRimsOfFilledHoles(const Holes& holes, const cv::Mat& fill_mask, int min_filled,
                           cv::Mat* rim) {
  std::vector<int> filled(holes.count, 0);
  for (int y = 0; y < fill_mask.rows; ++y)
    for (int x = 0; x < fill_mask.cols; ++x)
      if (fill_mask.at<uint8_t>(y, x)) ++filled[holes.labels.at<int>(y, x)];
  for (int y = 0; y < rim->rows; ++y)
    for (int x = 0; x < rim->cols; ++x)
      if (rim->at<uint8_t>(y, x) && filled[holes.labels.at<int>(y, x)] < min_filled)
        rim->at<uint8_t>(y, x) = 0;
}

cv::Mat SeeThroughRim(const RgbdFrame& key1, const cv::Mat& stereo,
                      const SeeThroughOptions& options, int ring_px, int min_samples) {
  if (options.rim_px <= 0) return {};
  auto disk = [](int r) {
    return cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});
  };
  // Holes are judged without the lines of hole pixels one or two pixels wide (3x3 opening), which
  // join objects that stand apart: a shelf's front edge, seen at a grazing angle, joins a clear
  // vase's hole to a dark object's, whose depth in front of the ring would then decide for both.
  const cv::Mat in_hole = key1.hole_mask != 0;
  cv::Mat whole, labels;
  cv::morphologyEx(in_hole, whole, cv::MORPH_OPEN, cv::Mat::ones(3, 3, CV_8UC1));
  const int count = cv::connectedComponents(whole, labels, 8, CV_32S);  // label 0: no hole
  if (count < 2) return {};
  // Every pixel within ring_px of a hole takes its label (the largest where two are that near):
  // the ring's measured pixels, and the hole pixels that the opening took away.
  cv::Mat near;
  labels.convertTo(near, CV_32F);
  cv::dilate(near, near, disk(ring_px));
  std::vector<std::vector<float>> inside(count), ring(count);
  std::vector<uint8_t> at_edge(count, 0);
  for (int y = 0; y < stereo.rows; ++y) {
    const uint8_t* w = whole.ptr<uint8_t>(y);
    const uint8_t* h = in_hole.ptr<uint8_t>(y);
    const int* l = labels.ptr<int>(y);
    const float* n = near.ptr<float>(y);
    const float* s = stereo.ptr<float>(y);
    const float* k = key1.depth.ptr<float>(y);
    const bool edge_row = y == 0 || y == stereo.rows - 1;
    for (int x = 0; x < stereo.cols; ++x) {
      if (w[x]) {
        if (s[x] > 0) inside[l[x]].push_back(s[x]);
        // A hole that reaches the image's edge is not seen whole (ICL-NUIM's invalid border
        // frame is one): what SGBM sees in it is the scene going on out of view.
        if (edge_row || x == 0 || x == stereo.cols - 1) at_edge[l[x]] = 1;
      } else if (!h[x] && n[x] > 0 && k[x] > 0) {
        ring[static_cast<int>(n[x])].push_back(k[x]);
      }
    }
  }
  std::vector<uint8_t> sees_through(count, 0);
  bool any = false;
  const size_t enough = static_cast<size_t>(min_samples);
  for (int i = 1; i < count; ++i) {
    if (at_edge[i] || inside[i].size() < enough || ring[i].size() < enough) continue;
    sees_through[i] = Median(std::move(inside[i])) >
                      (1.0 + options.ratio) * Median(std::move(ring[i]));
    any |= sees_through[i] != 0;
  }
  if (!any) return {};
  cv::Mat deep;  // hole pixels farther than see_through_rim_px from every measured pixel
  cv::erode(in_hole, deep, disk(options.rim_px));
  cv::Mat rim = cv::Mat::zeros(stereo.size(), CV_8UC1);
  for (int y = 0; y < rim.rows; ++y) {
    const uint8_t* h = in_hole.ptr<uint8_t>(y);
    const uint8_t* d = deep.ptr<uint8_t>(y);
    const float* n = near.ptr<float>(y);
    uint8_t* r = rim.ptr<uint8_t>(y);
    for (int x = 0; x < rim.cols; ++x)
      if (h[x] && !d[x] && sees_through[static_cast<int>(n[x])]) r[x] = 255;
  }
  return rim;
}

}  // namespace gf
