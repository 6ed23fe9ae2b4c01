#include "acquisition/realsense_bag.h"

#include "acquisition/errors.h"

#if GF_HAVE_ROSBAG
#include <geometry_msgs/Transform.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <spdlog/spdlog.h>
#include <std_msgs/Float32.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <opencv2/imgproc.hpp>
#include <regex>
#endif

namespace gf {

#if GF_HAVE_ROSBAG

namespace {

using ImagePtr = sensor_msgs::Image::ConstPtr;

// The image topics of one kind ("Depth", "Color") in librealsense's layout.
std::vector<std::string> ImageTopics(const rosbag::Bag& bag, const std::string& kind) {
  const std::regex pattern("^/device_[0-9]+/sensor_[0-9]+/" + kind + "_[0-9]+/image/data$");
  std::vector<std::string> topics;
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* c : view.getConnections())
    if (c->datatype == "sensor_msgs/Image" && std::regex_match(c->topic, pattern) &&
        std::find(topics.begin(), topics.end(), c->topic) == topics.end())
      topics.push_back(c->topic);
  std::sort(topics.begin(), topics.end());
  return topics;
}

std::string ChooseTopic(const std::string& path, const std::vector<std::string>& topics,
                        const std::string& wanted, const std::string& what,
                        const std::string& flag) {
  std::string listed;
  for (const std::string& t : topics) listed += (listed.empty() ? "" : ", ") + t;
  if (!wanted.empty()) {
    if (std::find(topics.begin(), topics.end(), wanted) == topics.end())
      throw InputError(path, "no " + what + " image stream on " + wanted +
                                 (topics.empty() ? "" : " (the bag has " + listed + ")"));
    return wanted;
  }
  if (topics.empty())
    throw InputError(path, "no " + what + " image stream (/device_N/sensor_N/" +
                               (what == "depth" ? "Depth" : "Color") +
                               "_N/image/data): not a RealSense recording, or one without " + what);
  if (topics.size() > 1)
    throw InputError(path,
                     "several " + what + " streams (" + listed + "): choose one with " + flag);
  return topics.front();
}

std::string StreamPrefix(const std::string& image_topic) {
  return image_topic.substr(0, image_topic.size() - std::string("/image/data").size());
}

// The first message of type M on any of `topics`, or null.
template <class M>
boost::shared_ptr<M> FirstMessage(const rosbag::Bag& bag, const std::vector<std::string>& topics) {
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  for (const rosbag::MessageInstance& m : view)
    if (boost::shared_ptr<M> message = m.instantiate<M>()) return message;
  return nullptr;
}

Camera CameraFromInfo(const std::string& path, const std::string& topic,
                      const sensor_msgs::CameraInfo& info) {
  Camera c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fx = info.K[0], c.fy = info.K[4], c.cx = info.K[2], c.cy = info.K[5];
  const bool distorted =
      std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; });
  if (distorted) {
    // librealsense's "Brown Conrady" coefficients are OpenCV's k1, k2, p1, p2, k3; ROS calls the
    // same model plumb_bob, and rational_polynomial adds k4-k6 (Camera::distortion). The inverse
    // and modified variants and the fisheye ones are not OpenCV's model.
    if (info.distortion_model != "Brown Conrady" && info.distortion_model != "plumb_bob" &&
        info.distortion_model != "rational_polynomial")
      throw InputError(path, topic + ": lens distortion model \"" + info.distortion_model +
                                 "\" with non-zero coefficients is not supported (OpenCV's "
                                 "Brown-Conrady is); pass --camera FILE with the lens in it");
    for (size_t i = 0; i < std::min<size_t>(8, info.D.size()); ++i) c.distortion[i] = info.D[i];
  }
  std::string problem;
  if (!c.CheckPlausible(&problem)) throw InputError(path, topic + ": " + problem);
  return c;
}

// A librealsense tf as stream_from_first: it takes points from the frame of its stream group's
// first stream (depth on a D400) into its stream's frame.
SE3 TransformOf(const geometry_msgs::Transform& t) {
  Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  if (!(q.norm() > 0.5)) q = Eigen::Quaterniond::Identity();
  return SE3(q.normalized(), Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z));
}

// The header stamp (seconds) of a serialized sensor_msgs/Image, read from its first fields (seq,
// stamp.sec, stamp.nsec) without decoding the pixels.
double HeaderStamp(const rosbag::MessageInstance& m, std::vector<uint8_t>* buffer) {
  buffer->resize(m.size());
  ros::serialization::OStream stream(buffer->data(), static_cast<uint32_t>(buffer->size()));
  m.write(stream);
  if (buffer->size() < 12) throw ros::Exception("image message shorter than its header");
  uint32_t sec = 0, nsec = 0;
  std::memcpy(&sec, buffer->data() + 4, 4);
  std::memcpy(&nsec, buffer->data() + 8, 4);
  return sec + nsec * 1e-9;
}

// Metres per depth unit: the recorded option, else the float librealsense 2.49+ appends to each
// depth image message, else the D400's default (1 mm, with a warning).
double DepthUnits(const rosbag::Bag& bag, const std::string& path, const std::string& prefix,
                  const std::string& depth_topic) {
  const std::string sensor = prefix.substr(0, prefix.rfind('/'));
  if (auto option = FirstMessage<std_msgs::Float32>(
          bag, {sensor + "/option/Depth_Units/value", sensor + "/option/Depth Units/value"}))
    if (option->data > 0) return option->data;
  rosbag::View view(bag, rosbag::TopicQuery(depth_topic));
  for (const rosbag::MessageInstance& m : view) {
    const ImagePtr image = m.instantiate<sensor_msgs::Image>();
    if (!image) break;
    const uint32_t length = ros::serialization::serializationLength(*image);
    if (m.size() != length + 4) break;
    std::vector<uint8_t> bytes(m.size());
    ros::serialization::OStream stream(bytes.data(), m.size());
    m.write(stream);
    float units = 0;
    std::memcpy(&units, bytes.data() + length, 4);
    if (units > 0) return units;
    break;
  }
  spdlog::warn("{}: no depth units recorded; using 1 mm (the D400's default)", path);
  return 0.001;
}

void CheckImage(const sensor_msgs::Image& image, int bytes_per_pixel, const std::string& where) {
  if (image.is_bigendian)
    throw InputError(where, "big-endian " + image.encoding + " image is not supported");
  if (image.width == 0 || image.height == 0 || image.step < image.width * bytes_per_pixel ||
      image.data.size() < static_cast<size_t>(image.step) * image.height)
    throw InputError(where, "image of " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + ", step " +
                                std::to_string(image.step) + ", holds only " +
                                std::to_string(image.data.size()) + " bytes");
}

cv::Mat View(const sensor_msgs::Image& image, int type) {
  return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type,
                 const_cast<uint8_t*>(image.data.data()), image.step);
}

cv::Mat DepthImage(const sensor_msgs::Image& image, const std::string& where) {
  if (image.encoding != "mono16" && image.encoding != "16UC1")
    throw InputError(where, "depth encoding \"" + image.encoding +
                                "\" is not supported (mono16 or 16UC1: 16-bit depth units)");
  CheckImage(image, 2, where);
  return View(image, CV_16UC1).clone();
}

cv::Mat ColorImage(const sensor_msgs::Image& image, const std::string& where) {
  std::string e = image.encoding;
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  struct Encoding {
    const char* name;
    int bytes, type, conversion;  // conversion -1: copy as it is
  };
  static const Encoding kEncodings[] = {
      {"rgb8", 3, CV_8UC3, cv::COLOR_RGB2BGR},
      {"bgr8", 3, CV_8UC3, -1},
      {"rgba8", 4, CV_8UC4, cv::COLOR_RGBA2BGR},
      {"bgra8", 4, CV_8UC4, cv::COLOR_BGRA2BGR},
      {"yuyv", 2, CV_8UC2, cv::COLOR_YUV2BGR_YUYV},
      {"yuv422", 2, CV_8UC2, cv::COLOR_YUV2BGR_UYVY},  // librealsense's name for UYVY
      {"uyvy", 2, CV_8UC2, cv::COLOR_YUV2BGR_UYVY},
      {"mono8", 1, CV_8UC1, cv::COLOR_GRAY2BGR},
      {"8uc1", 1, CV_8UC1, cv::COLOR_GRAY2BGR}};
  for (const Encoding& k : kEncodings) {
    if (e != k.name) continue;
    CheckImage(image, k.bytes, where);
    cv::Mat bgr;
    if (k.conversion < 0)
      bgr = View(image, k.type).clone();
    else
      cv::cvtColor(View(image, k.type), bgr, k.conversion);
    return bgr;
  }
  throw InputError(where, "colour encoding \"" + image.encoding + "\" is not supported");
}

}  // namespace

// A bag read in two passes: the header stamps of both streams first (to pair depth and colour,
// and to know the frame count), then the images, in bag order, as Next() asks for them.
class RealSenseBagSource : public FrameSource {
 public:
  RealSenseBagSource(const std::string& path, const FrameSourceOptions& options)
      : path_(path), options_(options) {
    try {
      bag_.open(path, rosbag::bagmode::Read);
      depth_topic_ = ChooseTopic(path, ImageTopics(bag_, "Depth"), options.bag_depth_topic,
                                 "depth", "--depth-topic");
      color_topic_ = ChooseTopic(path, ImageTopics(bag_, "Color"), options.bag_color_topic,
                                 "colour", "--color-topic");
      ReadCalibration();
      PairFrames();
      view_ = std::make_unique<rosbag::View>(bag_,
                                             rosbag::TopicQuery({depth_topic_, color_topic_}));
      next_message_ = view_->begin();
    } catch (const ros::Exception& e) {
      throw InputError(path, Unreadable(e.what()));
    }
  }

  std::string Kind() const override { return "realsense_bag"; }
  std::string Input() const override { return path_; }
  const CameraFile& camera_file() const override { return camera_; }
  DepthConvention depth_convention() const override { return convention_; }
  std::optional<int> FrameCount() const override { return static_cast<int>(pairs_.size()); }

  bool Next(RgbdFrame* frame) override {
    if (next_pair_ >= pairs_.size()) return false;
    const auto [d, c] = pairs_[next_pair_];
    const std::string where =
        path_ + " frame " + std::to_string(next_pair_) + " (depth stamp " + StampText(d) + ")";
    try {
      while (!depth_pending_.count(d) || (options_.load_color && !color_pending_.count(c))) {
        if (next_message_ == view_->end())
          throw InputError(where, "the bag ended before this frame's images");
        Keep(*next_message_);
        ++next_message_;
      }
    } catch (const ros::Exception& e) {
      throw InputError(where, Unreadable(e.what()));
    }
    RgbdFrame f;
    f.index = static_cast<int>(next_pair_);
    f.timestamp = depth_stamps_[d];
    f.timestamp_text = StampText(d);
    f.color_timestamp = color_stamps_[c];
    ProcessRawDepth(DepthImage(*depth_pending_[d], where), where, camera_, convention_, options_,
                    &f);
    depth_pending_.erase(d);
    if (options_.load_color) {
      f.color = ColorImage(*color_pending_[c], where);
      color_pending_.erase(c);
      if (f.color.cols != camera_.camera.width || f.color.rows != camera_.camera.height)
        throw InputError(where, "colour image of " + std::to_string(f.color.cols) + "x" +
                                    std::to_string(f.color.rows) + " differs from its camera_info");
    }
    *frame = std::move(f);
    ++next_pair_;
    return true;
  }

 private:
  static std::string Unreadable(const std::string& what) {
    return "unreadable RealSense bag (truncated, not indexed or corrupt): " + what;
  }

  std::string StampText(size_t depth_index) const {
    char text[64];
    std::snprintf(text, sizeof(text), "%.6f", depth_stamps_[depth_index]);
    return text;
  }

  // Intrinsics of both streams, their extrinsic and the depth units.
  void ReadCalibration() {
    const std::string depth = StreamPrefix(depth_topic_), color = StreamPrefix(color_topic_);
    auto info = [&](const std::string& prefix) {
      const std::string topic = prefix + "/info/camera_info";
      const auto message = FirstMessage<sensor_msgs::CameraInfo>(bag_, {topic});
      if (!message) throw InputError(path_, "no intrinsics (" + topic + ")");
      return CameraFromInfo(path_, topic, *message);
    };
    auto pose = [&](const std::string& prefix) {
      const auto message = FirstMessage<geometry_msgs::Transform>(bag_, {prefix + "/tf/0"});
      if (!message) throw InputError(path_, "no extrinsic (" + prefix + "/tf/0)");
      return TransformOf(*message);
    };
    double scale = 1.0 / DepthUnits(bag_, path_, depth, depth_topic_);
    if (std::abs(scale - std::round(scale)) < 1e-3 * scale) scale = std::round(scale);
    convention_ = DepthConvention::FromDepthScale(scale);
    if (!options_.camera_file.empty()) {
      camera_ = LoadCameraFile(options_.camera_file);
    } else {
      camera_.camera = info(color);
      const Camera depth_camera = info(depth);
      // Each tf takes points from the group's first stream's frame into its stream's.
      const SE3 color_from_depth = pose(color) * pose(depth).Inverse();
      // Depth recorded aligned to colour (the Viewer's "align" or a converted capture): the same
      // camera, nothing to register.
      const Camera& c = camera_.camera;
      const bool aligned =
          depth_camera.width == c.width && depth_camera.height == c.height &&
          depth_camera.fx == c.fx && depth_camera.fy == c.fy && depth_camera.cx == c.cx &&
          depth_camera.cy == c.cy && depth_camera.distortion == c.distortion &&
          color_from_depth.translation().norm() < 1e-9 &&
          color_from_depth.rotation().angularDistance(Eigen::Quaterniond::Identity()) < 1e-9;
      if (!aligned) {
        camera_.depth_camera = depth_camera;
        camera_.color_from_depth = color_from_depth;
        camera_.depth_registered_to_color = false;
      }
    }
    camera_.depth_scale = scale;
    // The D435's, D455's and D405's depth imagers have global shutters (the D415's rolls: give
    // it a camera file with depth_readout_s).
    if (options_.camera_file.empty()) camera_.depth_readout_s = 0.0;
  }

  // The header stamps of both streams, and the depth-colour pairs nearest in time.
  void PairFrames() {
    std::vector<uint8_t> buffer;
    rosbag::View view(bag_, rosbag::TopicQuery({depth_topic_, color_topic_}));
    for (const rosbag::MessageInstance& m : view)
      (m.getTopic() == depth_topic_ ? depth_stamps_ : color_stamps_)
          .push_back(HeaderStamp(m, &buffer));
    if (depth_stamps_.empty()) throw InputError(path_, "no depth frames on " + depth_topic_);
    if (color_stamps_.empty()) throw InputError(path_, "no colour frames on " + color_topic_);
    pairs_ = PairRecordedStreams(depth_stamps_, color_stamps_, options_.max_association_dt_s,
                                 path_);
    depth_wanted_.assign(depth_stamps_.size(), false);
    color_wanted_.assign(color_stamps_.size(), false);
    for (const auto& [d, c] : pairs_) depth_wanted_[d] = color_wanted_[c] = true;
  }

  // Holds the message's image when a pair still to come needs it.
  void Keep(const rosbag::MessageInstance& m) {
    const bool depth = m.getTopic() == depth_topic_;
    const size_t index = depth ? depth_seen_++ : color_seen_++;
    const std::vector<bool>& wanted = depth ? depth_wanted_ : color_wanted_;
    if (index >= wanted.size())
      throw InputError(path_, "more images on " + m.getTopic() + " than when it was opened");
    if (!wanted[index] || (!depth && !options_.load_color)) return;
    ImagePtr image = m.instantiate<sensor_msgs::Image>();
    if (!image) throw InputError(path_, m.getTopic() + ": not a sensor_msgs/Image");
    (depth ? depth_pending_ : color_pending_)[index] = image;
  }

  std::string path_;
  FrameSourceOptions options_;
  rosbag::Bag bag_;
  std::string depth_topic_, color_topic_;
  CameraFile camera_;
  DepthConvention convention_ = DepthConvention::Millimetres();
  std::vector<double> depth_stamps_, color_stamps_;
  std::vector<std::pair<size_t, size_t>> pairs_;  // (depth, colour) message indices
  std::vector<bool> depth_wanted_, color_wanted_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator next_message_;
  size_t next_pair_ = 0, depth_seen_ = 0, color_seen_ = 0;
  std::map<size_t, ImagePtr> depth_pending_, color_pending_;
};

bool RealSenseBagSupported() { return true; }

std::unique_ptr<FrameSource> OpenRealSenseBag(const std::string& path,
                                              const FrameSourceOptions& options) {
  return std::make_unique<RealSenseBagSource>(path, options);
}

#else

bool RealSenseBagSupported() { return false; }

std::unique_ptr<FrameSource> OpenRealSenseBag(const std::string& path,
                                              const FrameSourceOptions&) {
  throw InputError(path,
                   "this build reads no .bag files (built without librosbag-storage-dev; "
                   "`make deps` installs it)");
}

#endif

}  // namespace gf
