// Scoring what the sensor missed and what the fill gave against a synthetic capture's ground
// truth (glassfusion synth: gt/label/, gt/visible_depth/, gt/depth/), per material.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/rgbd_frame.h"

namespace gf {

inline constexpr int kSynthMaterials = 5;  // synth::Material values scored

// The name of material m (synth::MaterialName).
std::string MaterialName(int m);

// The sensor's holes per material over every frame of the scene (ground-truth labels).
struct SensorHoles {
  std::vector<size_t> holes = std::vector<size_t>(kSynthMaterials, 0);
  std::vector<size_t> pixels = std::vector<size_t>(kSynthMaterials, 0);
};

// Reads the capture in scene_dir through its frame source; *first receives its first frame.
// Throws InputError when a frame's label is missing.
SensorHoles MeasureSensorHoles(const std::string& scene_dir, RgbdFrame* first);

// The keyframes' fill scored per material against the depth of what the colour camera sees there
// (through clear glass: the background).
struct FillScore {
  std::vector<size_t> holes = std::vector<size_t>(kSynthMaterials, 0);
  std::vector<size_t> filled = std::vector<size_t>(kSynthMaterials, 0);
  std::vector<size_t> good = std::vector<size_t>(kSynthMaterials, 0);  // within 3%
  std::vector<std::vector<float>> errors = std::vector<std::vector<float>>(kSynthMaterials);
  // Filled clear-glass pixels that take the glass's own depth instead of the background's where
  // the map does not mark glass (glass_mask.png): the goal is none. Where it marks glass, the map's
  // transparent surfels complete the keyframe with the glass's depth on purpose; counted apart.
  size_t clear_glass_at_glass_depth = 0;
  size_t clear_glass_marked_at_glass_depth = 0;
  double Rate(const std::vector<size_t>& n, int m) const {
    return holes[m] ? static_cast<double>(n[m]) / holes[m] : 0.0;
  }
};

// One keyframe's fill scored into *score: filled_m and truth_m (the depth of what the colour
// camera sees) CV_64F metres, 0 where none; holes (the sensor's) and label (synth::Material)
// CV_8U. For clear glass, first_surface_m (CV_64F, the first surface along each ray) and glass
// (CV_8U, the keyframe's glass_mask) split the fills at the glass's own depth; either may be empty
// (not counted). The run-folder scorer below and the in-memory tests share it.
void ScoreKeyframeFill(const cv::Mat& filled_m, const cv::Mat& holes, const cv::Mat& label,
                       const cv::Mat& truth_m, const cv::Mat& first_surface_m,
                       const cv::Mat& glass, FillScore* score);

// Every keyframe of the run in run_dir (keyframes/<ts>.depth_filled.png, hole_mask.png,
// glass_mask.png) against the capture in scene_dir. Throws InputError on a missing mask.
FillScore ScoreFill(const std::string& scene_dir, const std::string& run_dir);

}  // namespace gf
