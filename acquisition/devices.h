// Live RGB-D devices and recordings behind optional libraries (OpenNI2, libfreenect).
//
// When GlassFusion is built without a library (GF_WITH_OPENNI2 / GF_WITH_FREENECT OFF, or its
// Debian package missing), these functions still exist: the *Available() query returns false and
// every other call throws std::runtime_error saying which library is missing and how to get it.
//
// OpenNI2 notes (Debian's OpenNI2 2.2, checked here):
//  - `Dummy` is OpenNI2's software device: 320x240 depth (1 mm units, mostly 0) and RGB888 colour
//    at 30 fps, with no field of view, so intrinsics come from --camera or a nominal 525 px at 640.
//  - OpenNI::shutdown() crashes after the Dummy device was opened, even with every stream destroyed
//    first, so GlassFusion initialises OpenNI2 once per process and never shuts it down.
//  - Its .oni player does not deliver frames of recordings made from the Dummy device (its file
//    driver spins); OpenOpenNI2Source reports that as a timeout error naming the file.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "acquisition/frame_source.h"

namespace gf {

// True when this build includes OpenNI2 support.
bool OpenNI2Available();
// URIs of the OpenNI2 devices that are connected now (may be empty).
std::vector<std::string> ListOpenNI2Devices();

struct OpenNI2Options {
  int timeout_ms = 2000;       // longest wait for one frame before giving up, milliseconds
  bool register_depth = true;  // ask the device to register depth to colour where it can
  bool Check(std::string* message = nullptr) const;
};

// An OpenNI2 device or recording as a FrameSource. uri: "" = first device, "Dummy", a device URI,
// or a path to an .oni file (then FrameCount() is the recording's depth frame count). Throws
// InputError naming the uri when it cannot be opened or delivers no frame in time.
std::unique_ptr<FrameSource> OpenOpenNI2Source(const std::string& uri,
                                               const FrameSourceOptions& options,
                                               const OpenNI2Options& openni2 = {});

// Records `frames` depth frames (and colour, when the device has it) from `uri` to an .oni file,
// written under a temporary name and renamed when complete. Returns the frames recorded.
int RecordOni(const std::string& uri, const std::string& oni_path, int frames,
              const OpenNI2Options& openni2 = {});

// True when this build includes libfreenect support.
bool FreenectAvailable();
// Number of Kinect v1 devices libfreenect sees now.
int CountFreenectDevices();
// Kinect v1 number `index` through libfreenect: raw 11-bit disparity (2047 kept as a hole) and
// 640x480 RGB, registered to colour with --camera or NominalKinectV1Calibration().
std::unique_ptr<FrameSource> OpenFreenectSource(int index, const FrameSourceOptions& options);

}  // namespace gf
