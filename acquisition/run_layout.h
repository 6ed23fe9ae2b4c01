// The layout of a run folder, in one place: the folder sink (pipeline/run_sink.h) writes these
// files and every reader (the reports, the evaluation, compare, batch, the demo, colmap-export)
// finds them here. README's "Outputs" says what each holds.
//
//   trajectory.txt  camera.json  report.json  report.html  map.ply  mesh.ply
//   keyframes/<name>.<image>.png        (KeyframeImage)
//   undistorted/{color,depth}/<file>    (IndexedFileName, run_folder.h)
//   compare:  compare.json  with_fill/  without_fill/  <map>_<view>.png
#pragma once

#include <string>

namespace gf {

// A keyframe's images in keyframes/, <name>.<image>.png.
enum class KeyframeImage {
  kHoleMask,        // 8-bit, 255 where the sensor gave no depth
  kDepthFilled,     // 16-bit millimetres: the sensor's depth with the holes filled
  kFillConfidence,  // 8-bit, 0-255 for a filled pixel's confidence 0-1
  kFillOverlay,     // colour with the filled pixels tinted by source
  kColor,           // the keyframe's colour image
  kModelFill,       // 8-bit, 255 where the map's completion filled it
  kGlassMask,       // 8-bit, 255 where the map's transparent surfels cover it
};

class RunLayout {
 public:
  static constexpr const char* kTrajectory = "trajectory.txt";  // TUM world_from_camera
  static constexpr const char* kCamera = "camera.json";
  static constexpr const char* kReport = "report.json";
  static constexpr const char* kPage = "report.html";
  static constexpr const char* kMap = "map.ply";
  static constexpr const char* kMesh = "mesh.ply";
  static constexpr const char* kKeyframes = "keyframes";
  static constexpr const char* kCompare = "compare.json";        // compare's figures
  static constexpr const char* kWithFill = "with_fill";          // compare's two run folders
  static constexpr const char* kWithoutFill = "without_fill";

  // "hole_mask", "depth_filled", ... (the file name's <image>).
  static const char* ImageName(KeyframeImage image);
  // keyframes/<name>.<image>.png, relative to the run folder.
  static std::string Keyframe(const std::string& name, KeyframeImage image);
  // The keyframe's name of a file name in keyframes/ that holds `image` ("" for another file).
  static std::string KeyframeOf(const std::string& file_name, KeyframeImage image);
  // undistorted/<relative>, the pinhole set: color/<file> and depth/<file> (IndexedFileName),
  // camera.json, camera_intrinsic.json (Open3D's), trajectory.log (Redwood).
  static std::string Undistorted(const std::string& relative);

  // A run folder, for reading its files.
  explicit RunLayout(std::string dir) : dir_(std::move(dir)) {}
  const std::string& dir() const { return dir_; }
  // dir/relative.
  std::string Path(const std::string& relative) const;
  // dir/keyframes/<name>.<image>.png.
  std::string Path(const std::string& name, KeyframeImage image) const;
  // compare's rendering of one map from one viewpoint ("camera", "above"): <map>_<view>.png.
  static std::string Rendering(bool with_fill, const std::string& view);

  // compare's with_fill/ or without_fill/ run folder inside this one.
  RunLayout Map(bool with_fill) const;

 private:
  std::string dir_;
};

}  // namespace gf
