// `glassfusion capture --device D --out DIR [--frames N]`: records any frame source (a live
// device, OpenNI2's Dummy device, an .oni file) to a TUM-format folder that every GlassFusion
// command can reprocess offline. Ctrl-C stops a live capture cleanly: the frames so far are kept
// and the folder is finished; DIR appears only once it is complete.
#pragma once

#include <string>

namespace gf {

struct CaptureOptions {
  std::string device;       // dummy | openni2[:URI] | freenect[:INDEX] | an .oni file
  std::string out_dir;      // TUM folder to create (must not exist or be empty)
  int frames = 0;           // frames to record; 0 = until the input ends or Ctrl-C
  std::string camera_file;  // intrinsics to use instead of the device's
  bool Check(std::string* message = nullptr) const;
};

// Returns the number of frames written.
int RunCapture(const CaptureOptions& options);

}  // namespace gf
