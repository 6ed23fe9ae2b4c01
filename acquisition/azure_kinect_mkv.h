// Azure Kinect and Orbbec Femto recordings: a Matroska `.mkv` as `k4arecorder` (or Orbbec's
// K4A wrapper) writes it, read with FFmpeg's libavformat (Debian's libavformat-dev).
//
// What is read, in the Azure Kinect Sensor SDK's layout (src/record/internal/matroska_*.cpp):
//  - the tracks named DEPTH (raw 16-bit millimetres, FOURCC b16g, stored big-endian) and COLOR
//    (MJPG, or raw NV12, YUY2 or BGRA), each frame a Matroska block; IR and IMU are ignored;
//  - the device clock: a block's time plus the file's K4A_START_OFFSET_NS tag; a frame's timestamp
//    is its depth block's, in seconds; depth and colour are paired by time as in a RealSense bag;
//  - the calibration attachment `calibration.json` (the device's factory calibration): both
//    cameras' intrinsics in the Brown-Conrady model the SDK uses, which is OpenCV's rational model
//    (Camera::distortion, 8 coefficients), made per mode from the track tags K4A_DEPTH_MODE and
//    K4A_COLOR_MODE; the depth-to-colour extrinsic; depth is then registered to colour by
//    ProcessRawDepth (RegisterDepthToColor, both lenses applied).
// The depth camera's modes NFOV_UNBINNED (640x576) and NFOV_2X2BINNED (320x288) are read. The wide
// modes (WFOV_*) see a circle whose corners the lens model maps to no ray: refused, naming the mode.
//
// Errors: a missing, truncated, corrupt or non-Matroska file, a missing track or calibration, an
// unsupported mode or codec, a depth frame of the wrong size, is an InputError naming the file and
// what is wrong, at open or at the frame where it is met. libavformat reads a damaged file
// mostly silently (a cut file ends early; garbage only logs): its warnings are caught, and a file
// whose blocks end before its stated duration is reported as truncated.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "acquisition/camera.h"
#include "acquisition/frame_source.h"

namespace gf {

// Whether this build reads .mkv files (libavformat was found).
bool AzureKinectMkvSupported();

// Opens an Azure Kinect / Femto .mkv as a FrameSource of kind "azure_kinect_mkv".
std::unique_ptr<FrameSource> OpenAzureKinectMkv(const std::string& path,
                                                const FrameSourceOptions& options);

// How an Azure Kinect camera mode takes its image from the sensor: the calibration's intrinsics
// are normalised to the sensor; a mode bins it to binned_width x binned_height, then crops
// width x height from (crop_x, crop_y). Pixels.
struct AzureKinectMode {
  int binned_width = 0, binned_height = 0;
  int crop_x = 0, crop_y = 0;
  int width = 0, height = 0;
};
// The depth modes NFOV_UNBINNED, NFOV_2X2BINNED, WFOV_UNBINNED, WFOV_2X2BINNED, PASSIVE_IR.
std::optional<AzureKinectMode> AzureKinectDepthMode(const std::string& name);
// The colour modes by their height, as K4A_COLOR_MODE ends ("MJPG_720P": 720, 1080, 1440, 1536,
// 2160, 3072; the sensor is 4:3, the 16:9 modes crop it).
std::optional<AzureKinectMode> AzureKinectColorMode(int height);

// camera.json's content from an Azure Kinect calibration.json (its text) for a depth mode and a
// colour mode: the colour camera, the depth camera, color_from_depth, depth in millimetres, the
// depth camera's global shutter (a time-of-flight sensor: depth_readout_s 0). Throws InputError
// naming `where` on bad JSON, a missing camera, a lens model other than Brown-Conrady, a
// non-zero centre of distortion (not in OpenCV's model), or intrinsics that are not plausible.
CameraFile AzureKinectCalibration(const std::string& json_text, const std::string& depth_mode,
                                  int color_height, const std::string& where);

// The inverse, for writing recordings in tests: calibration.json text holding these two cameras
// (each made for its mode) and the extrinsic, as the SDK lays it out.
std::string AzureKinectCalibrationJson(const Camera& depth_camera, const std::string& depth_mode,
                                       const Camera& color_camera, int color_height,
                                       const SE3& color_from_depth);

}  // namespace gf
