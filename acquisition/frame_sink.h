// FrameSink: where frames go to be kept (a TUM-format folder, memory for tests), so that any
// source, live or recorded, can be saved and reprocessed offline.
//
// Usage:
//   gf::TumFolderSink sink("capture-01", source->camera_file());
//   while (source->Next(&frame)) sink.Write(frame);
//   sink.Close();  // only now does capture-01/ appear, complete
//
// Thread-safety: one thread at a time.
#pragma once

#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/rgbd_frame.h"

namespace gf {

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void Write(const RgbdFrame& frame) = 0;
  // Finishes the output; after Close() the output is complete and Write() may not be called.
  virtual void Close() = 0;
};

struct TumFolderSinkOptions {
  double depth_scale = 5000.0;  // depth PNG units per metre (TUM's 5000: 0.2 mm steps, 13.1 m max)
  bool Check(std::string* message = nullptr) const;
};

// Writes a TUM RGB-D folder: rgb/<ts>.png, depth/<ts>.png (16-bit, depth_scale units, 0 = hole),
// rgb.txt, depth.txt and camera.json (the colour camera; depth is written registered to colour).
// <ts> is the frame's timestamp_text, or its timestamp with 6 decimals.
// Everything is written under <out>.partial-<pid>/ and renamed to <out> by Close(), so a crash or
// an error never leaves a folder that looks complete; a sink destroyed without Close() removes its
// partial folder. Throws InputError when <out> already exists and is not an empty folder.
class TumFolderSink : public FrameSink {
 public:
  TumFolderSink(std::string out_dir, CameraFile camera, TumFolderSinkOptions options = {});
  ~TumFolderSink() override;
  void Write(const RgbdFrame& frame) override;
  void Close() override;
  int frames_written() const { return static_cast<int>(depth_lines_.size()); }

 private:
  std::string out_dir_;
  std::string partial_dir_;
  CameraFile camera_;
  TumFolderSinkOptions options_;
  std::vector<std::string> rgb_lines_;
  std::vector<std::string> depth_lines_;
  bool closed_ = false;
};

// Keeps copies of the frames, for tests.
class InMemoryFrameSink : public FrameSink {
 public:
  void Write(const RgbdFrame& frame) override;
  void Close() override { closed = true; }
  std::vector<RgbdFrame> frames;
  bool closed = false;
};

}  // namespace gf
