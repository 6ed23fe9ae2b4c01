// Carrying validated stereo fills from earlier keyframes into a keyframe's holes.
//
// A surface the depth sensor cannot measure (glass, a dark or shiny patch) stays a hole in every
// frame, and each keyframe's stereo fills only part of it: the part its own pair and third view
// support. The earlier keyframes saw the same surface from nearby, and their validated fills,
// moved into this keyframe with the tracked poses, cover much of the rest. A hole pixel takes a
// carried depth only where at least `min_agreeing` earlier keyframes put a point on it within
// `agreement` of one another (their median); one keyframe's stray fill is not enough. Where the
// keyframe's own stereo filled a pixel and the earlier keyframes agree on another depth, the
// consensus replaces it (`correct_own_fills`): several pairs outvote one. Measured pixels are never
// changed, and only each keyframe's own stereo fills are carried on, never carried ones, so an
// error cannot feed on itself.
//
// It also spreads an error that several keyframes share. Its measured effect (tuning and check
// sets) is in docs/experiments/.
//
// No threads, no I/O. The free functions keep no state; a FillCarrier keeps the last keyframes'
// fill points and is used from one thread. Usage:
//   gf::FillCarrier carrier(camera, {});
//   for each keyframe, in order:
//     gf::CarriedFillResult c = carrier.Next(key1, world_from_key1, &stereo_result);  // or nullptr
#pragma once

#include <Eigen/Core>
#include <deque>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "fill/stereo_fill.h"

namespace gf {

struct FillCarryOptions {
  int max_keyframes = 15;   // earlier keyframes whose fills are carried (0: off); the caller keeps
                            // this many
  int min_agreeing = 2;     // earlier keyframes that must agree on a pixel's depth
  double agreement = 0.02;  // relative depth difference within which they agree (of the median)
  bool correct_own_fills = true;  // the consensus replaces the keyframe's own fill where it differs
                                  // by more than `agreement`
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

// The pixels one keyframe's stereo filled, as points in the world frame (metres). Empty when the
// stereo filled nothing.
struct KeyframeFillPoints {
  std::vector<Eigen::Vector3f> world_points;
};

// The own stereo fills of `fill` (pixels with fill_mask set and source kStereo or kColmap) moved
// into the world frame.
KeyframeFillPoints FillPointsInWorld(const StereoFillResult& fill, const SE3& world_from_camera,
                                     const Camera& camera);

struct CarriedFillResult {
  cv::Mat filled_depth;    // CV_32F metres: sensor depth, own fills, carried fills
  cv::Mat fill_mask;       // CV_8U: 255 where a hole was filled (own or carried)
  cv::Mat source;          // CV_8U DepthSource: kCarried where the depth came from other keyframes
  cv::Mat confidence;      // CV_32F [0, 1]: carried pixels get the share of candidates that agree
  cv::Mat corroborated;    // CV_8U: the own fill's DepthFill::corroborated (never a carried pixel)
  int filled_pixels = 0;   // all filled pixels, own and carried
  int carried_pixels = 0;  // holes the own stereo left empty that earlier keyframes filled
  int corrected_pixels = 0;  // own fills replaced by the earlier keyframes' consensus
  std::string BriefReport() const;
};

// key1: the keyframe (metric depth, hole mask); own: its own stereo fill, or null / unsuccessful
// when it had none; earlier: the earlier keyframes' fill points (any order, nulls skipped).
CarriedFillResult CarryFills(const RgbdFrame& key1, const SE3& world_from_key1,
                             const StereoFillResult* own,
                             const std::vector<const KeyframeFillPoints*>& earlier,
                             const Camera& camera, const FillCarryOptions& options);

// CarryFills over a stream of keyframes: keeps the own fill points of the last
// options.max_keyframes keyframes (none when it is 0).
class FillCarrier {
 public:
  FillCarrier(const Camera& camera, const FillCarryOptions& options);
  // Carries the kept keyframes' fills into key1, then keeps key1's own fills (own: its stereo
  // result, or null when it had none).
  CarriedFillResult Next(const RgbdFrame& key1, const SE3& world_from_key1,
                         const StereoFillResult* own);

 private:
  Camera camera_;
  FillCarryOptions options_;
  std::deque<KeyframeFillPoints> earlier_;
};

}  // namespace gf
