// Where a reconstruction's outputs go: a run folder (DESIGN.md's layout) or memory (for tests).
//
// A run folder holds trajectory.txt (TUM format, world_from_camera, the input's depth
// timestamps), camera.json (the camera of the run's images; keyframe depth is millimetres),
// report.json, map.ply (the surfel map, surfels/ply.h) and keyframes/ (names in DESIGN.md):
//   <ts>.hole_mask.png     8-bit HoleCode (0 valid, 1 no return, 2 out of range, 3 shadow)
//   <ts>.depth_filled.png  16-bit millimetres: sensor depth plus filled pixels, 0 still empty
//   <ts>.fill_overlay.png  colour image, filled pixels green (cyan: carried from earlier
//                          keyframes; brighter = more confident), holes still empty magenta
//   <ts>.color.png         the keyframe's colour image (lossless; colmap-export uses it)
// These keep the input's image geometry (its lens distortion, as camera.json states). The same
// keyframes on the ideal pinhole camera, as an Open3D / Redwood dataset folder, are in
// undistorted/:
//   color/<index>_<ts>.png  colour, undistorted (bilinear); <index> is the frame's, 6 digits
//   depth/<index>_<ts>.png  filled depth (16-bit millimetres, 0 = none), undistorted (nearest)
//   camera.json             the pinhole camera (no distortion), depth_scale 1000
//   camera_intrinsic.json   the same as Open3D's PinholeCameraIntrinsic JSON
//   trajectory.log          the keyframes' world_from_camera in file order (Redwood / Open3D .log)
// Every file is written atomically (a temporary name, then renamed), so an interrupted run never
// leaves a truncated file that looks complete. The folder is a RunFolder
// (acquisition/run_folder.h): its marker .glassfusion-run lists every file the run writes, and
// its lock keeps a second run out while this one writes.
//
// Thread-safety: WriteCamera comes first; then WriteKeyframe may be called from one thread while
// another calls the rest.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"
#include "acquisition/run_folder.h"
#include "acquisition/trajectory.h"
#include "fill/fill_carry.h"
#include "pipeline/run_report.h"
#include "surfels/surfel_map.h"

namespace gf {

// What the final map offers a keyframe's holes (FusionStage::RenderFills).
struct MapCompletion {
  cv::Mat depth;       // CV_32F metres: the map's fill surface where it is confirmed from the
                       // keyframe's side; 0 = none
  cv::Mat confidence;  // CV_32F, 0-1 where depth > 0: how far the map's depth there is trusted
  // A valid sensor pixel of the keyframe within occluder_px pixels that lies nearer than the
  // offered depth by more than occluder_margin (relative) hides it: the map's surface there is
  // behind the object the keyframe saw at the hole's rim, not what the hole holds.
  int occluder_px = 0;
  double occluder_margin = 0.03;
  // CV_8U, 255 where the map's nearest surface is transparent (clear glass, DepthSource::
  // kTransparent): the keyframe's glass mask. Empty when the map looks for no glass.
  cv::Mat glass;
};

class RunSink {
 public:
  virtual ~RunSink() = default;
  // A keyframe's hole mask, filled depth (fill.filled_depth, metres) and, when it has colour, its
  // overlay and colour image. `name` is KeyframeName(frame). Throws InputError when it cannot be
  // written.
  virtual void WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                             const CarriedFillResult& fill) = 0;
  virtual void WriteTrajectory(const Trajectory& trajectory) = 0;
  virtual void WriteCamera(const CameraFile& camera) = 0;
  virtual void WriteReport(const RunReport& report) = 0;  // report.json
  // map.ply (surfels/ply.h): the stable surfels of the run's surfel map.
  virtual void WriteMap(const std::vector<Surfel>& surfels) = 0;
  // Completes keyframe `name` (written before) from the map: its hole pixels that its filled
  // depth leaves empty take the offered depth where there is one and nothing of the keyframe hides
  // it (CompleteFromModel), with the offer's confidence. Returns the pixels completed. Throws
  // InputError when the keyframe cannot be read back or rewritten, std::out_of_range when no
  // keyframe of that name was written.
  // Several threads may complete different keyframes at once, after PrepareCompletion() named
  // them all (in the order the outputs should list them).
  virtual int CompleteKeyframe(const std::string& name, const MapCompletion& offer) = 0;
  virtual void PrepareCompletion(const std::vector<std::string>& names) { (void)names; }
  // The colour image (CV_8UC3) of keyframe `name` as written, or an empty image where there is
  // none (no colour, not written, or this sink keeps no images).
  virtual cv::Mat KeyframeColor(const std::string& name) const {
    (void)name;
    return {};
  }
  // Where the outputs go, for messages ("memory" for the in-memory sink).
  virtual std::string Where() const = 0;
};

// A run folder. The constructor opens it as a RunFolder that the sink holds (and with it the
// lock) until it is destroyed: the folder must be new or empty, or hold an earlier run and
// `options.earlier` be kReplace (--force), in which case only the files that run listed in its
// marker are removed; a folder of the user's (no marker), the input itself, a folder that contains
// it or one inside it, and a folder another run is writing are refused. Throws InputError.
class FolderRunSink : public RunSink {
 public:
  FolderRunSink(const std::string& out_dir, const RunFolder::Options& options);
  // The same with options.earlier = replace ? kReplace : kRefuse and no inputs.
  FolderRunSink(const std::string& out_dir, bool replace);
  // The run in `folder`/`subfolder` (compare's with_fill/ and without_fill/): its files are
  // recorded in `folder`'s marker, which must outlive the sink.
  FolderRunSink(RunFolder* folder, const std::string& subfolder);
  // Records `relative` (a file the caller writes into the run, e.g. mesh.ply, report.html) in the
  // marker and returns its path; RunFolder::File.
  std::string File(const std::string& relative);
  void WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                     const CarriedFillResult& fill) override;
  void WriteTrajectory(const Trajectory& trajectory) override;
  void WriteCamera(const CameraFile& camera) override;
  void WriteReport(const RunReport& report) override;
  void WriteMap(const std::vector<Surfel>& surfels) override;
  // Rewrites <name>.depth_filled.png and the pinhole depth, and writes <name>.model_fill.png (255
  // where the model completed the keyframe) and, when the offer has one, <name>.glass_mask.png.
  int CompleteKeyframe(const std::string& name, const MapCompletion& offer) override;
  // Claims the files the completion may add, in this order (the run folder's list of its files
  // then comes out the same on every run, whichever thread writes first).
  void PrepareCompletion(const std::vector<std::string>& names) override;
  cv::Mat KeyframeColor(const std::string& name) const override;
  std::string Where() const override { return out_dir_; }

 private:
  // image on the pinhole camera (as it is without distortion).
  cv::Mat Undistort(const cv::Mat& image, int interpolation) const;
  std::unique_ptr<RunFolder> owned_;  // the folder, when the sink opened it
  RunFolder* folder_;
  std::string prefix_;   // "" or "<subfolder>/"
  std::string out_dir_;  // folder_->dir() + "/" + prefix_
  // cv::remap maps onto the pinhole camera, set by WriteCamera; empty: no distortion.
  cv::Mat undistort_x_, undistort_y_;
  std::mutex mutex_;
  struct Written {
    std::string name;          // KeyframeName
    std::string pinhole_file;  // its file in undistorted/color and undistorted/depth
  };
  std::map<int, Written> keyframes_;  // written keyframes by frame index
};

// Keeps everything in memory, for tests.
class InMemoryRunSink : public RunSink {
 public:
  struct Keyframe {
    RgbdFrame frame;
    CarriedFillResult fill;  // filled_depth and confidence completed by CompleteKeyframe
    cv::Mat model_fill;      // CV_8U: 255 where CompleteKeyframe completed it (empty before)
    cv::Mat glass_mask;      // CV_8U: the offer's glass mask (MapCompletion::glass)
  };
  void WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                     const CarriedFillResult& fill) override;
  void WriteTrajectory(const Trajectory& trajectory) override;
  void WriteCamera(const CameraFile& camera) override;
  void WriteReport(const RunReport& report) override;
  void WriteMap(const std::vector<Surfel>& surfels) override;
  int CompleteKeyframe(const std::string& name, const MapCompletion& offer) override;
  cv::Mat KeyframeColor(const std::string& name) const override;
  std::string Where() const override { return "memory"; }

  // Read after the run.
  std::map<std::string, Keyframe> keyframes;
  Trajectory trajectory;
  CameraFile camera;
  RunReport report;
  std::vector<Surfel> map;
  bool map_written = false;

 private:
  mutable std::mutex mutex_;
};

// Sets *filled_depth (CV_32F metres) to offer.depth (same size, 0 = none) on the pixels of
// hole_mask (CV_8U, non-zero: the sensor's holes; not projector shadows) that it leaves empty and
// where no sensor pixel (hole_mask 0) within offer.occluder_px lies in front of the offered depth
// (MapCompletion); *completed (CV_8U) gets 255 there and *confidence (CV_32F, may be null) the
// offer's confidence. Returns their count.
int CompleteFromModel(const cv::Mat& hole_mask, const MapCompletion& offer, cv::Mat* filled_depth,
                      cv::Mat* confidence, cv::Mat* completed);

// The overlay written as <ts>.fill_overlay.png (see above).
cv::Mat FillOverlay(const cv::Mat& color, const CarriedFillResult& fill);

// The tints (BGR) overlays give pixels the map completed (orange) and clear glass (cyan).
inline const cv::Scalar kCompletedTint(0, 165, 255);
inline const cv::Scalar kGlassTint(255, 200, 0);
// *overlay takes, on mask's pixels, color half-mixed with tint (color and *overlay CV_8UC3, mask
// CV_8U, all one size).
void TintOverlay(const cv::Mat& color, const cv::Mat& mask, const cv::Scalar& tint,
                 cv::Mat* overlay);

}  // namespace gf
