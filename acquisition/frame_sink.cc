#include "acquisition/frame_sink.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/bounds.h"

namespace fs = std::filesystem;

namespace gf {

bool TumFolderSinkOptions::Check(std::string* message) const {
  // Units per metre: 16-bit PNG depth must hold at least half a metre.
  FieldCheck c(message);
  c.Above("depth_scale", depth_scale, 0, 2 * 65535.0,
          "leaves no room for half a metre in 16 bits");
  return c.ok();
}

TumFolderSink::TumFolderSink(std::string out_dir, CameraFile camera, TumFolderSinkOptions options)
    : out_dir_(std::move(out_dir)), camera_(std::move(camera)), options_(options) {
  std::string problem;
  if (!options_.Check(&problem)) throw InputError(out_dir_, "bad writer options: " + problem);
  partial_dir_ = StageFolder(out_dir_);
  std::error_code ec;
  fs::create_directories(fs::path(partial_dir_) / "rgb", ec);
  if (!ec) fs::create_directories(fs::path(partial_dir_) / "depth", ec);
  if (ec) throw InputError(out_dir_, "cannot create output folder: " + ec.message());
}

TumFolderSink::~TumFolderSink() {
  if (!closed_) {
    std::error_code ec;
    fs::remove_all(partial_dir_, ec);
  }
}

void TumFolderSink::Write(const RgbdFrame& frame) {
  GF_CHECK(!closed_, "Write() after Close()");
  GF_CHECK(frame.depth.type() == CV_32FC1, "frame depth must be CV_32FC1 metres");
  if (frame.color.empty())
    throw InputError(out_dir_, "frame " + std::to_string(frame.index) +
                                   " has no colour image; a TUM folder needs one per frame");
  std::string ts = frame.timestamp_text;
  if (ts.empty()) {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.6f", frame.timestamp);
    ts = buffer;
  }
  const std::string rgb_name = "rgb/" + ts + ".png";
  const std::string depth_name = "depth/" + ts + ".png";
  WriteImage((fs::path(partial_dir_) / rgb_name).string(), frame.color);
  WriteImage((fs::path(partial_dir_) / depth_name).string(),
             DepthToRaw(frame.depth, DepthConvention::ScaledUnits(options_.depth_scale)));
  char color_time[64];
  std::snprintf(color_time, sizeof(color_time), "%.6f",
                frame.color_timestamp > 0 ? frame.color_timestamp : frame.timestamp);
  rgb_lines_.push_back(std::string(frame.color_timestamp > 0 ? color_time : ts) + " " + rgb_name);
  depth_lines_.push_back(ts + " " + depth_name);
}

void TumFolderSink::Close() {
  GF_CHECK(!closed_, "Close() called twice");
  auto index = [](const char* what, const std::vector<std::string>& lines) {
    std::ostringstream s;
    s << "# " << what << "\n# written by GlassFusion\n# timestamp filename\n";
    for (const auto& l : lines) s << l << "\n";
    return s.str();
  };
  WriteTextFileAtomically((fs::path(partial_dir_) / "rgb.txt").string(),
                          index("color images", rgb_lines_));
  WriteTextFileAtomically((fs::path(partial_dir_) / "depth.txt").string(),
                          index("depth maps", depth_lines_));
  CameraFile written = camera_;
  written.depth_scale = options_.depth_scale;
  written.depth_registered_to_color = true;  // frames arrive registered to colour
  written.depth_camera.reset();
  SaveCameraFile((fs::path(partial_dir_) / "camera.json").string(), written);
  PublishFolder(partial_dir_, out_dir_);
  closed_ = true;
}

void InMemoryFrameSink::Write(const RgbdFrame& frame) {
  GF_CHECK(!closed, "Write() after Close()");
  RgbdFrame copy = frame;
  copy.color = frame.color.clone();
  copy.depth = frame.depth.clone();
  copy.hole_mask = frame.hole_mask.clone();
  frames.push_back(std::move(copy));
}

}  // namespace gf
