// FrameSource: one interface for every way RGB-D frames arrive (dataset folders, recordings,
// live devices), and the folder readers for TUM RGB-D and Redwood / Open3D layouts.
//
// Usage:
//   gf::FrameSourceOptions options;
//   std::unique_ptr<gf::FrameSource> source = gf::OpenFrameSource("tum_fr1_xyz_head", options);
//   gf::RgbdFrame frame;
//   while (source->Next(&frame)) { ... frame.depth (metres), frame.hole_mask ... }
//
// Errors: OpenFrameSource and Next throw InputError("<file>: <problem>") for unreadable or
// inconsistent input (missing index, a timestamp that is not a finite number, undecodable image,
// wrong bit depth, size mismatch, images under kMinImageWidthPx x kMinImageHeightPx). Folder
// sources check the first frame's image sizes against the camera when they open.
// Thread-safety: a source is used from one thread at a time.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/associate.h"
#include "acquisition/camera.h"
#include "acquisition/depth.h"
#include "acquisition/rgbd_frame.h"

namespace gf {

struct FrameSourceOptions {
  bool load_color = true;              // false: frames carry depth only (faster, e.g. for info)
  DepthConversionOptions depth;        // sensor range used to classify holes
  double max_association_dt_s = 0.02;  // TUM colour/depth association window, seconds
  std::string camera_file;             // overrides <folder>/camera.json when not empty
  std::string depth_folder;            // Redwood: depth subfolder; empty = depth/ or depth_noisy/
  ShadowOptions shadows;               // projector-shadow classification of no-return holes
  // RealSense .bag: the image topics to read where the bag holds several depth or colour
  // streams (e.g. /device_0/sensor_0/Depth_0/image/data); empty = the only one there is.
  std::string bag_depth_topic;
  std::string bag_color_topic;
  bool Check(std::string* message = nullptr) const;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // "tum", "redwood", "memory", ...
  virtual std::string Kind() const = 0;
  // What was opened (folder, file or device URI).
  virtual std::string Input() const = 0;
  virtual const CameraFile& camera_file() const = 0;
  const Camera& camera() const { return camera_file().camera; }
  virtual DepthConvention depth_convention() const = 0;
  // Number of frames Next() will deliver, when known in advance (not for live devices).
  virtual std::optional<int> FrameCount() const = 0;
  // Fills *frame with the next frame; false at the end of the input.
  virtual bool Next(RgbdFrame* frame) = 0;
};

// The conversion every source applies to a raw depth image (named `where` in errors): checks it
// against the convention and the (depth) camera size, converts to metres, classifies holes (no
// return, out of range, projector shadow), counts them in the sensor's image, and registers depth
// to colour when the camera file says it is not registered. Fills frame->depth, hole_mask and
// sensor_holes. Throws InputError naming `where`.
void ProcessRawDepth(const cv::Mat& raw, const std::string& where, const CameraFile& camera,
                     const DepthConvention& convention, const FrameSourceOptions& options,
                     RgbdFrame* frame);

// One frame of a folder dataset before its images are read.
struct FolderFrameEntry {
  double timestamp = 0;
  std::string timestamp_text;
  double color_timestamp = 0;
  std::string color_path;
  std::string depth_path;
};

// A dataset folder as a list of entries; loads the images of one entry per Next().
class FolderFrameSource : public FrameSource {
 public:
  FolderFrameSource(std::string kind, std::string input, CameraFile camera,
                    DepthConvention convention, std::vector<FolderFrameEntry> entries,
                    FrameSourceOptions options);
  std::string Kind() const override { return kind_; }
  std::string Input() const override { return input_; }
  const CameraFile& camera_file() const override { return camera_; }
  DepthConvention depth_convention() const override { return convention_; }
  std::optional<int> FrameCount() const override { return static_cast<int>(entries_.size()); }
  bool Next(RgbdFrame* frame) override;

  // Entries whose colour file is not there (Next() would fail on them when loading colour).
  int MissingColorFiles() const;

  // Frames that the index listed but could not pair (e.g. depth without colour within 20 ms).
  int unmatched_depth = 0;
  int unmatched_color = 0;
  int listed_depth = 0;
  int listed_color = 0;

 private:
  std::string kind_;
  std::string input_;
  CameraFile camera_;
  DepthConvention convention_;
  // The first frame's images against the camera (and their least size), from their headers: a
  // camera.json that does not describe the images is refused before anything is allocated for
  // its size. Throws InputError naming the image.
  static void CheckFirstFrame(const FolderFrameEntry& first, const CameraFile& camera);

  std::vector<FolderFrameEntry> entries_;
  FrameSourceOptions options_;
  size_t next_ = 0;
};

// TUM RGB-D folder: rgb.txt and depth.txt ("timestamp filename" lines, # comments), camera.json.
// Colour and depth are associated one-to-one by nearest timestamp within max_association_dt_s, as
// TUM's associate.py does; unmatched frames are dropped and counted (and logged). Both index files
// must be regular files (a missing one, a folder or a dangling link is an InputError naming it).
std::unique_ptr<FolderFrameSource> OpenTumFolder(const std::string& folder,
                                                 const FrameSourceOptions& options);
// Redwood / Open3D folder: image/ or color/ (or rgb/) and depth/ with files paired by sorted name.
std::unique_ptr<FolderFrameSource> OpenRedwoodFolder(const std::string& folder,
                                                     const FrameSourceOptions& options);

// Raw Kinect v1 folder: 11-bit disparity images (*.pgm / *.png whose name starts with "d-" or
// contains "depth") paired by sorted name with colour images (name starts with "r-" or contains
// "color"/"rgb"). With an INDEX.txt it is a libfreenect fakenect recording: the index lists
// d-<time>-<counter>.pgm and r-<time>-<counter>.ppm files (a-*.dump accelerometer lines are
// ignored) and colour is associated to depth by time. Depth is in the IR camera: frames are
// registered to colour with camera.json's depth_camera and color_from_depth, or with
// NominalKinectV1Calibration() when the folder has no camera.json (logged as a warning).
std::unique_ptr<FolderFrameSource> OpenKinectRawFolder(const std::string& folder,
                                                       const FrameSourceOptions& options);

// A typical Kinect v1 calibration (N. Burrus' published sample calibration, rounded): colour and
// IR cameras at 640x480 and the IR-to-colour transform (about 2.3 cm apart). Use a calibration of
// the actual device where one exists: units differ by a few pixels.
CameraFile NominalKinectV1Calibration();

// Frames held in memory: for tests and for piping one stage's output into another.
class InMemoryFrameSource : public FrameSource {
 public:
  InMemoryFrameSource(CameraFile camera, std::vector<RgbdFrame> frames);
  std::string Kind() const override { return "memory"; }
  std::string Input() const override { return "memory"; }
  const CameraFile& camera_file() const override { return camera_; }
  DepthConvention depth_convention() const override {
    return DepthConvention::FromDepthScale(camera_.depth_scale);
  }
  std::optional<int> FrameCount() const override { return static_cast<int>(frames_.size()); }
  bool Next(RgbdFrame* frame) override;

 private:
  CameraFile camera_;
  std::vector<RgbdFrame> frames_;
  size_t next_ = 0;
};

// What kind of input a path is: "tum" (a folder with rgb.txt or depth.txt, even a broken one),
// "redwood", "fakenect", "kinect_raw", "oni", "realsense_bag", "azure_kinect_mkv", or "" when
// unrecognised.
std::string DetectInputKind(const std::string& input);

// Opens any supported input, detected from what it is: a TUM, Redwood or raw Kinect folder, an .oni
// recording, a RealSense .bag (acquisition/realsense_bag.h), an Azure Kinect .mkv
// (acquisition/azure_kinect_mkv.h), or a live device ("dummy" = OpenNI2's software device,
// "openni2[:URI]", "freenect[:INDEX]"). Throws InputError naming the input when it is missing or of no known kind.
std::unique_ptr<FrameSource> OpenFrameSource(const std::string& input,
                                             const FrameSourceOptions& options);

}  // namespace gf
