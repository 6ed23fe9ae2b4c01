// Test support: writes an Azure Kinect recording, a Matroska `.mkv` in the layout of the Azure
// Kinect Sensor SDK's k4arecorder, with FFmpeg's libavformat (Debian's libavformat-dev), so that
// the .mkv reader (acquisition/azure_kinect_mkv.h) can be tested on files whose content is known.
//
// What is written, as k4arecorder writes it:
//  - segment title "Azure Kinect"; global tags K4A_START_OFFSET_NS, K4A_DEPTH_DELAY_NS "0",
//    K4A_WIRED_SYNC_MODE "STANDALONE";
//  - TimestampScale 1000 ns: block times are microseconds since the start offset;
//  - a video track "COLOR" (track tag K4A_COLOR_MODE, e.g. "MJPG_720P") and a video track "DEPTH"
//    (track tag K4A_DEPTH_MODE, e.g. "NFOV_UNBINNED"), both codec V_MS/VFW/FOURCC with a
//    BITMAPINFOHEADER of positive height (rows top-down):
//      DEPTH  FOURCC b16g, 16 bits: millimetres, 16-bit big-endian, 0 = no reading;
//      COLOR  MJPG: FOURCC MJPG, 24 bits, one JPEG per block;
//             BGRA: BI_RGB (0), 32 bits, 4 bytes per pixel B, G, R, A (A = 255);
//  - the attachment "calibration.json" (application/octet-stream, tag K4A_CALIBRATION_FILE).
// IR and IMU tracks are not written.
//
// FFmpeg's Matroska muxer cannot write this layout directly (it writes raw video with FOURCC 0, a
// negative height and millisecond ticks), so the file is patched in place when it is finished:
// see k4a_mkv_writer.cc.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace gf::testing {

struct K4aMkvOptions {
  // K4A_DEPTH_MODE: NFOV_UNBINNED (640x576), NFOV_2X2BINNED (320x288), WFOV_UNBINNED (1024x1024)
  // or WFOV_2X2BINNED (512x512).
  std::string depth_mode = "NFOV_UNBINNED";
  // The colour mode by its height, pixels: 720 (1280x720), 1080, 1440, 1536 (2048x1536), 2160,
  // 3072 (4096x3072). K4A_COLOR_MODE is "<color_format>_<color_height>P", e.g. "MJPG_720P".
  int color_height = 720;
  // "MJPG" (each frame a JPEG of jpeg_quality, 0-100) or "BGRA" (raw, lossless).
  std::string color_format = "MJPG";
  int jpeg_quality = 95;
  // K4A_START_OFFSET_NS: the device time of block time 0, nanoseconds.
  int64_t start_offset_ns = 0;
  // Bytes of the calibration.json attachment; empty: the file has no attachment.
  std::string calibration_json;
};

// One capture. An empty image writes no block for its track at this time (a dropped frame).
struct K4aMkvFrame {
  int64_t time_us = 0;  // block time of both images, microseconds since the start offset (>= 0)
  cv::Mat depth_mm;     // CV_16UC1 of the depth mode's size, millimetres, 0 = no reading
  cv::Mat color_bgr;    // CV_8UC3 of the colour mode's size
};

// Writes one recording. Frames are written in the order given; a block time earlier than the
// previous one of its track is an error. Throws std::invalid_argument on bad options or frames
// and std::runtime_error (with libavformat's message) when writing fails.
class K4aMkvWriter {
 public:
  K4aMkvWriter(const std::string& path, const K4aMkvOptions& options);
  // Finishes the file when Finish() was not called (errors ignored).
  ~K4aMkvWriter();
  K4aMkvWriter(const K4aMkvWriter&) = delete;
  K4aMkvWriter& operator=(const K4aMkvWriter&) = delete;

  void Write(const K4aMkvFrame& frame);
  // Writes the index and trailer, closes the file and patches it to k4arecorder's layout.
  // Nothing may be written after it; a second call does nothing.
  void Finish();

 private:
  struct Muxer;  // the libavformat state
  std::string path_;
  K4aMkvOptions options_;
  cv::Size depth_size_, color_size_;  // pixels
  std::unique_ptr<Muxer> muxer_;
};

}  // namespace gf::testing
