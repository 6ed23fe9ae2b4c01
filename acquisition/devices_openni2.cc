// OpenNI2 half of devices.h; compiled against OpenNI2 when GF_HAVE_OPENNI2, else a stub.
#include <stdexcept>

#include "acquisition/devices.h"
#include "acquisition/errors.h"

#if GF_HAVE_OPENNI2
#include <OpenNI.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "acquisition/file_util.h"
#include "acquisition/bounds.h"
#endif

namespace gf {

bool OpenNI2Options::Check(std::string* message) const {
  // A frame waited for longer than a day is a device that stopped.
  FieldCheck c(message);
  c.In("timeout_ms", timeout_ms, 1, 86'400'000.0, "is longer than a day");
  return c.ok();
}

#if GF_HAVE_OPENNI2

namespace {

// Once per process, never shut down (see devices.h).
void EnsureOpenNI2() {
  static const openni::Status status = openni::OpenNI::initialize();
  if (status != openni::STATUS_OK)
    throw std::runtime_error(std::string("OpenNI2 initialisation failed: ") +
                             openni::OpenNI::getExtendedError());
}

std::string DisplayName(const std::string& uri) { return uri.empty() ? "openni2" : uri; }

bool IsOniPath(const std::string& uri) {
  return uri.size() > 4 && uri.compare(uri.size() - 4, 4, ".oni") == 0;
}

// The device and its streams, shared by the source and the recorder. Debian's Dummy driver
// crashes in its own thread once any Dummy colour stream is stopped or destroyed, so the Dummy
// device is opened once per process with both streams running, borrowed by every user and never
// closed. Other devices are owned and closed normally.
struct OpenNI2Device {
  openni::Device* device = nullptr;
  openni::VideoStream* depth = nullptr;
  openni::VideoStream* color = nullptr;
  bool has_color = false;
  bool owned = true;
  std::string name;

  explicit OpenNI2Device(const std::string& uri) : name(DisplayName(uri)) {
    EnsureOpenNI2();
    if (uri == "Dummy") {
      static OpenNI2Device* dummy = new OpenNI2Device(uri, /*shared=*/true);
      *this = *dummy;
      owned = false;
      return;
    }
    Open(uri);
  }
  ~OpenNI2Device() {
    if (!owned) return;
    if (depth) {
      depth->stop();
      depth->destroy();
    }
    if (color) {
      color->stop();
      color->destroy();
    }
    if (device) device->close();
    delete depth;
    delete color;
    delete device;
  }
  OpenNI2Device(const OpenNI2Device&) = default;
  OpenNI2Device& operator=(const OpenNI2Device&) = default;

  // Starts depth, and colour when wanted (the shared Dummy device runs both already).
  void Start(bool with_color) {
    if (!owned) return;
    if (depth->start() != openni::STATUS_OK)
      throw InputError(name,
                       std::string("cannot start depth: ") + openni::OpenNI::getExtendedError());
    if (has_color && !(with_color && color->start() == openni::STATUS_OK)) {
      color->destroy();
      delete color;
      color = nullptr;
      has_color = false;
    }
  }
  // Waits for one frame of `stream`; false on timeout.
  static bool Read(openni::VideoStream* stream, int timeout_ms, openni::VideoFrameRef* frame) {
    openni::VideoStream* streams[] = {stream};
    int ready = -1;
    if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, timeout_ms) != openni::STATUS_OK)
      return false;
    return stream->readFrame(frame) == openni::STATUS_OK && frame->isValid();
  }

 private:
  OpenNI2Device(const std::string& uri, bool /*shared*/) : name(uri) {
    Open(uri);
    owned = true;
    Start(true);
    owned = false;  // never stopped or closed
  }
  void Open(const std::string& uri) {
    if (IsOniPath(uri) && !IsRegularFile(uri)) throw InputError(uri, "file not found");
    device = new openni::Device;
    depth = new openni::VideoStream;
    if (device->open(uri.empty() ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK) {
      const std::string error = openni::OpenNI::getExtendedError();
      delete depth;
      delete device;
      depth = nullptr;
      device = nullptr;
      throw InputError(name, std::string(IsOniPath(uri) ? "cannot open recording (truncated or "
                                                          "not an .oni file?): "
                                                        : "cannot open OpenNI2 device: ") +
                                 error);
    }
    if (!device->hasSensor(openni::SENSOR_DEPTH) ||
        depth->create(*device, openni::SENSOR_DEPTH) != openni::STATUS_OK)
      throw InputError(name, "has no depth stream");
    if (device->hasSensor(openni::SENSOR_COLOR)) {
      color = new openni::VideoStream;
      has_color = color->create(*device, openni::SENSOR_COLOR) == openni::STATUS_OK;
      if (!has_color) {
        delete color;
        color = nullptr;
      }
    }
  }
};

Camera CameraFromStream(const openni::VideoStream& stream, int width, int height, bool* known) {
  Camera c;
  c.width = width;
  c.height = height;
  const double hfov = stream.getHorizontalFieldOfView(), vfov = stream.getVerticalFieldOfView();
  *known = hfov > 0.1 && vfov > 0.1 && hfov < 3.0 && vfov < 3.0;
  c.fx = *known ? (width / 2.0) / std::tan(hfov / 2.0) : 525.0 * width / 640.0;
  c.fy = *known ? (height / 2.0) / std::tan(vfov / 2.0) : 525.0 * width / 640.0;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  return c;
}

class OpenNI2Source : public FrameSource {
 public:
  OpenNI2Source(const std::string& uri, const FrameSourceOptions& options,
                const OpenNI2Options& openni2)
      : dev_(uri), uri_(uri), options_(options), openni2_(openni2) {
    std::string problem;
    if (!openni2_.Check(&problem)) throw InputError(dev_.name, "bad OpenNI2 options: " + problem);
    openni::PlaybackControl* playback = dev_.device->getPlaybackControl();
    if (playback) {
      playback->setRepeatEnabled(false);
      frame_count_ = playback->getNumberOfFrames(*dev_.depth);
    }
    bool registered = !dev_.has_color;
    if (dev_.has_color && openni2.register_depth &&
        dev_.device->isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR))
      registered = dev_.device->setImageRegistrationMode(
                       openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) == openni::STATUS_OK;
    const openni::VideoMode depth_mode = dev_.depth->getVideoMode();
    switch (depth_mode.getPixelFormat()) {
      case openni::PIXEL_FORMAT_DEPTH_1_MM:
        convention_ = DepthConvention::Millimetres();
        break;
      case openni::PIXEL_FORMAT_DEPTH_100_UM:
        convention_ = DepthConvention::ScaledUnits(10000.0);
        break;
      default:
        throw InputError(dev_.name, "unsupported depth pixel format " +
                                        std::to_string(depth_mode.getPixelFormat()));
    }
    if (!options.camera_file.empty()) {
      camera_ = LoadCameraFile(options.camera_file);
    } else {
      bool known = false;
      const openni::VideoMode color_mode = dev_.has_color ? dev_.color->getVideoMode() : depth_mode;
      camera_.camera =
          CameraFromStream(dev_.has_color ? *dev_.color : *dev_.depth, color_mode.getResolutionX(),
                           color_mode.getResolutionY(), &known);
      if (!registered) {
        bool depth_known = false;
        camera_.depth_camera = CameraFromStream(*dev_.depth, depth_mode.getResolutionX(),
                                                depth_mode.getResolutionY(), &depth_known);
        camera_.depth_registered_to_color = false;
        known = known && depth_known;
      }
      if (!known)
        spdlog::warn(
            "{}: device reports no field of view; using nominal intrinsics (fx = 525 px at "
            "640 wide). Pass --camera FILE for real ones",
            dev_.name);
    }
    camera_.depth_scale = convention_.units_per_metre();
    dev_.Start(options.load_color);
  }

  std::string Kind() const override { return IsOniPath(uri_) ? "oni" : "openni2"; }
  std::string Input() const override { return dev_.name; }
  const CameraFile& camera_file() const override { return camera_; }
  DepthConvention depth_convention() const override { return convention_; }
  std::optional<int> FrameCount() const override {
    return frame_count_ >= 0 ? std::optional<int>(frame_count_) : std::nullopt;
  }

  bool Next(RgbdFrame* frame) override {
    if (frame_count_ >= 0 && next_index_ >= frame_count_) return false;
    openni::VideoFrameRef depth, color;
    auto read_depth = [&] {
      if (!OpenNI2Device::Read(dev_.depth, openni2_.timeout_ms, &depth))
        throw InputError(dev_.name, "no depth frame within " + std::to_string(openni2_.timeout_ms) +
                                        " ms (frame " + std::to_string(next_index_) +
                                        (frame_count_ >= 0 ? " of " + std::to_string(frame_count_)
                                                           : std::string()) +
                                        "); recording truncated or player stalled");
    };
    auto read_color = [&] {
      if (!OpenNI2Device::Read(dev_.color, openni2_.timeout_ms, &color))
        throw InputError(dev_.name,
                         "no colour frame within " + std::to_string(openni2_.timeout_ms) + " ms");
    };
    read_depth();
    if (dev_.has_color) {
      read_color();
      // The two streams run independently: drop whichever lags by more than half a frame so the
      // pair shows one moment (live devices only; a recording keeps every depth frame).
      const int fps = std::max(1, dev_.depth->getVideoMode().getFps());
      const int64_t half_frame_us = 500000 / fps;
      for (int tries = 0; tries < 8; ++tries) {
        const int64_t dt =
            static_cast<int64_t>(color.getTimestamp()) - static_cast<int64_t>(depth.getTimestamp());
        if (dt < -half_frame_us) {
          read_color();
        } else if (dt > half_frame_us && frame_count_ < 0) {
          read_depth();
        } else {
          break;
        }
      }
    }
    RgbdFrame f;
    f.index = next_index_;
    f.timestamp = depth.getTimestamp() * 1e-6;
    char text[64];
    std::snprintf(text, sizeof(text), "%.6f", f.timestamp);
    f.timestamp_text = text;
    const cv::Mat raw(depth.getHeight(), depth.getWidth(), CV_16UC1,
                      const_cast<void*>(depth.getData()), depth.getStrideInBytes());
    ProcessRawDepth(raw.clone(), dev_.name + " depth frame " + std::to_string(next_index_), camera_,
                    convention_, options_, &f);
    if (dev_.has_color) {
      if (color.getVideoMode().getPixelFormat() != openni::PIXEL_FORMAT_RGB888)
        throw InputError(dev_.name, "unsupported colour pixel format " +
                                        std::to_string(color.getVideoMode().getPixelFormat()));
      const cv::Mat rgb(color.getHeight(), color.getWidth(), CV_8UC3,
                        const_cast<void*>(color.getData()), color.getStrideInBytes());
      cv::cvtColor(rgb, f.color, cv::COLOR_RGB2BGR);
      f.color_timestamp = color.getTimestamp() * 1e-6;
      if (f.color.cols != camera_.camera.width || f.color.rows != camera_.camera.height)
        throw InputError(dev_.name, "colour frame size differs from the camera");
    }
    *frame = std::move(f);
    ++next_index_;
    return true;
  }

 private:
  OpenNI2Device dev_;
  std::string uri_;
  FrameSourceOptions options_;
  OpenNI2Options openni2_;
  CameraFile camera_;
  DepthConvention convention_ = DepthConvention::Millimetres();
  int frame_count_ = -1;
  int next_index_ = 0;
};

}  // namespace

bool OpenNI2Available() { return true; }

std::vector<std::string> ListOpenNI2Devices() {
  EnsureOpenNI2();
  openni::Array<openni::DeviceInfo> infos;
  openni::OpenNI::enumerateDevices(&infos);
  std::vector<std::string> uris;
  for (int i = 0; i < infos.getSize(); ++i) uris.emplace_back(infos[i].getUri());
  return uris;
}

std::unique_ptr<FrameSource> OpenOpenNI2Source(const std::string& uri,
                                               const FrameSourceOptions& options,
                                               const OpenNI2Options& openni2) {
  return std::make_unique<OpenNI2Source>(uri, options, openni2);
}

int RecordOni(const std::string& uri, const std::string& oni_path, int frames,
              const OpenNI2Options& openni2) {
  GF_CHECK(frames > 0, "record at least one frame");
  OpenNI2Device dev(uri);
  dev.Start(true);
  int recorded = 0;
  WriteFileAtomically(oni_path, [&](const std::string& temporary) {
    openni::Recorder recorder;
    if (recorder.create(temporary.c_str()) != openni::STATUS_OK ||
        recorder.attach(*dev.depth) != openni::STATUS_OK)
      throw InputError(oni_path,
                       std::string("cannot record: ") + openni::OpenNI::getExtendedError());
    if (dev.has_color) recorder.attach(*dev.color);
    recorder.start();
    for (; recorded < frames; ++recorded) {
      openni::VideoFrameRef frame, color;
      if (!OpenNI2Device::Read(dev.depth, openni2.timeout_ms, &frame)) break;
      if (dev.has_color && !OpenNI2Device::Read(dev.color, openni2.timeout_ms, &color)) break;
    }
    recorder.stop();
    recorder.destroy();
  });
  return recorded;
}

#else

namespace {
[[noreturn]] void NoOpenNI2() {
  throw std::runtime_error(
      "GlassFusion was built without OpenNI2: install libopenni2-dev and rebuild with "
      "-DGF_WITH_OPENNI2=ON");
}
}  // namespace

bool OpenNI2Available() { return false; }
std::vector<std::string> ListOpenNI2Devices() { NoOpenNI2(); }
std::unique_ptr<FrameSource> OpenOpenNI2Source(const std::string&, const FrameSourceOptions&,
                                               const OpenNI2Options&) {
  NoOpenNI2();
}
int RecordOni(const std::string&, const std::string&, int, const OpenNI2Options&) { NoOpenNI2(); }

#endif

}  // namespace gf
