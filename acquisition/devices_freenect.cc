// libfreenect half of devices.h; compiled against libfreenect when GF_HAVE_FREENECT, else a stub.
#include <stdexcept>

#include "acquisition/devices.h"
#include "acquisition/errors.h"

#if GF_HAVE_FREENECT
#include <libfreenect.h>
#include <spdlog/spdlog.h>
#include <sys/time.h>

#include <chrono>
#include <cstring>
#include <opencv2/imgproc.hpp>
#endif

namespace gf {

#if GF_HAVE_FREENECT

namespace {

// Kinect v1 through libfreenect's asynchronous API, driven synchronously: Next() pumps
// freenect_process_events until a new depth and a new colour image have arrived. No threads.
class FreenectSource : public FrameSource {
 public:
  FreenectSource(int index, const FrameSourceOptions& options)
      : name_("freenect:" + std::to_string(index)), options_(options) {
    if (freenect_init(&context_, nullptr) < 0 || !context_)
      throw InputError(name_, "libfreenect initialisation failed (no USB access?)");
    freenect_select_subdevices(context_, FREENECT_DEVICE_CAMERA);
    const int count = freenect_num_devices(context_);
    if (count <= index) {
      freenect_shutdown(context_);
      throw InputError(name_, "no Kinect v1 with this index (libfreenect sees " +
                                  std::to_string(count < 0 ? 0 : count) + ")");
    }
    if (freenect_open_device(context_, &device_, index) < 0) {
      freenect_shutdown(context_);
      throw InputError(name_, "cannot open the Kinect (in use, or no USB permission?)");
    }
    camera_ = options.camera_file.empty() ? NominalKinectV1Calibration()
                                          : LoadCameraFile(options.camera_file);
    freenect_set_user(device_, this);
    freenect_set_depth_mode(
        device_, freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_11BIT));
    freenect_set_video_mode(
        device_, freenect_find_video_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_VIDEO_RGB));
    freenect_set_depth_callback(device_, &FreenectSource::OnDepth);
    freenect_set_video_callback(device_, &FreenectSource::OnVideo);
    if (freenect_start_depth(device_) < 0 || freenect_start_video(device_) < 0) {
      Release();
      throw InputError(name_, "cannot start the depth and colour streams");
    }
    start_ = std::chrono::steady_clock::now();
  }
  ~FreenectSource() override { Release(); }

  std::string Kind() const override { return "freenect"; }
  std::string Input() const override { return name_; }
  const CameraFile& camera_file() const override { return camera_; }
  DepthConvention depth_convention() const override { return DepthConvention::KinectV1Raw11Bit(); }
  std::optional<int> FrameCount() const override { return std::nullopt; }

  bool Next(RgbdFrame* frame) override {
    new_depth_ = new_video_ = false;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (!(new_depth_ && (new_video_ || !options_.load_color))) {
      timeval timeout{0, 100000};
      if (freenect_process_events_timeout(context_, &timeout) < 0)
        throw InputError(name_, "USB error while streaming");
      if (std::chrono::steady_clock::now() > deadline)
        throw InputError(name_, "no frame within 2 s (cable unplugged?)");
    }
    RgbdFrame f;
    f.index = next_index_++;
    f.timestamp = depth_time_;
    f.color_timestamp = video_time_;
    char text[64];
    std::snprintf(text, sizeof(text), "%.6f", f.timestamp);
    f.timestamp_text = text;
    ProcessRawDepth(depth_.clone(), name_ + " depth frame " + std::to_string(f.index), camera_,
                    DepthConvention::KinectV1Raw11Bit(), options_, &f);
    if (options_.load_color) cv::cvtColor(video_, f.color, cv::COLOR_RGB2BGR);
    *frame = std::move(f);
    return true;
  }

 private:
  double Now() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  static void OnDepth(freenect_device* device, void* data, uint32_t) {
    auto* self = static_cast<FreenectSource*>(freenect_get_user(device));
    self->depth_ = cv::Mat(480, 640, CV_16UC1, data).clone();
    self->depth_time_ = self->Now();
    self->new_depth_ = true;
  }
  static void OnVideo(freenect_device* device, void* data, uint32_t) {
    auto* self = static_cast<FreenectSource*>(freenect_get_user(device));
    self->video_ = cv::Mat(480, 640, CV_8UC3, data).clone();
    self->video_time_ = self->Now();
    self->new_video_ = true;
  }
  void Release() {
    if (device_) {
      freenect_stop_depth(device_);
      freenect_stop_video(device_);
      freenect_close_device(device_);
      device_ = nullptr;
    }
    if (context_) {
      freenect_shutdown(context_);
      context_ = nullptr;
    }
  }

  std::string name_;
  FrameSourceOptions options_;
  CameraFile camera_;
  freenect_context* context_ = nullptr;
  freenect_device* device_ = nullptr;
  std::chrono::steady_clock::time_point start_;
  cv::Mat depth_, video_;
  double depth_time_ = 0, video_time_ = 0;
  bool new_depth_ = false, new_video_ = false;
  int next_index_ = 0;
};

}  // namespace

bool FreenectAvailable() { return true; }

int CountFreenectDevices() {
  freenect_context* context = nullptr;
  if (freenect_init(&context, nullptr) < 0 || context == nullptr)
    throw std::runtime_error("libfreenect initialisation failed (no USB access?)");
  const int count = freenect_num_devices(context);
  freenect_shutdown(context);
  if (count < 0) throw std::runtime_error("libfreenect could not enumerate devices");
  return count;
}

std::unique_ptr<FrameSource> OpenFreenectSource(int index, const FrameSourceOptions& options) {
  return std::make_unique<FreenectSource>(index, options);
}

#else

namespace {
[[noreturn]] void NoFreenect() {
  throw std::runtime_error(
      "GlassFusion was built without libfreenect: install libfreenect-dev and rebuild with "
      "-DGF_WITH_FREENECT=ON");
}
}  // namespace

bool FreenectAvailable() { return false; }
int CountFreenectDevices() { NoFreenect(); }
std::unique_ptr<FrameSource> OpenFreenectSource(int, const FrameSourceOptions&) { NoFreenect(); }

#endif

}  // namespace gf
