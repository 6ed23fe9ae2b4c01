// Live RGB-D devices behind optional libraries (OpenNI2, libfreenect).
//
// When GlassFusion is built without a library (GF_WITH_OPENNI2 / GF_WITH_FREENECT OFF, or its
// Debian package missing), these functions still exist: the *Available() query returns false and
// every other call throws std::runtime_error saying which library is missing and how to get it.
#pragma once

#include <string>
#include <vector>

namespace gf {

// True when this build includes OpenNI2 support.
bool OpenNI2Available();
// URIs of the OpenNI2 devices that are connected now (may be empty).
std::vector<std::string> ListOpenNI2Devices();

// True when this build includes libfreenect support.
bool FreenectAvailable();
// Number of Kinect v1 devices libfreenect sees now.
int CountFreenectDevices();

}  // namespace gf
