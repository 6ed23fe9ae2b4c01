#include "acquisition/azure_kinect_mkv.h"

#include "acquisition/errors.h"

#if GF_HAVE_LIBAV
extern "C" {
#include <libavformat/avformat.h>
#include <libavutil/log.h>
}
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#endif

namespace gf {

#if GF_HAVE_LIBAV

namespace {

// libavformat reports most damage only through its log. While a reader calls into it, the
// warnings and errors of this thread are collected; elsewhere they are dropped (nothing else in
// GlassFusion uses libav).
thread_local std::vector<std::string>* g_av_messages = nullptr;

void CollectAvLog(void* context, int level, const char* format, va_list arguments) {
  if (level > AV_LOG_WARNING || !g_av_messages) return;
  char line[512];
  int print_prefix = 0;
  av_log_format_line2(context, level, format, arguments, line, sizeof(line), &print_prefix);
  std::string text(line);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  g_av_messages->push_back(text);
}

class CollectAvMessages {
 public:
  explicit CollectAvMessages(std::vector<std::string>* into) : previous_(g_av_messages) {
    static std::once_flag once;
    std::call_once(once, [] { av_log_set_callback(CollectAvLog); });
    g_av_messages = into;
  }
  ~CollectAvMessages() { g_av_messages = previous_; }

 private:
  std::vector<std::string>* previous_;
};

std::string AvError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof(text));
  return text;
}

std::string Tag(const AVDictionary* tags, const char* key) {
  const AVDictionaryEntry* e = av_dict_get(tags, key, nullptr, 0);
  return e ? e->value : "";
}

constexpr uint32_t FourCc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(a) | static_cast<uint32_t>(b) << 8 |
         static_cast<uint32_t>(c) << 16 | static_cast<uint32_t>(d) << 24;
}

// A Matroska file opened with libavformat, closed when it goes.
struct OpenedFile {
  AVFormatContext* context = nullptr;
  OpenedFile(const std::string& path, std::vector<std::string>* messages) {
    CollectAvMessages collect(messages);
    const int status = avformat_open_input(&context, path.c_str(), nullptr, nullptr);
    if (status < 0)
      throw InputError(path, "not a readable Matroska file: " + AvError(status) +
                                 (messages->empty() ? "" : " (" + messages->front() + ")"));
    if (std::string(context->iformat->name).find("matroska") == std::string::npos) {
      avformat_close_input(&context);
      throw InputError(path, "not a Matroska file");
    }
  }
  ~OpenedFile() { avformat_close_input(&context); }
  OpenedFile(const OpenedFile&) = delete;
  OpenedFile& operator=(const OpenedFile&) = delete;
};

// The colour mode's height from K4A_COLOR_MODE ("MJPG_720P" -> 720), 0 when it says none.
int ColorModeHeight(const std::string& mode) {
  const size_t underscore = mode.rfind('_');
  if (underscore == std::string::npos || mode.back() != 'P') return 0;
  try {
    return std::stoi(mode.substr(underscore + 1));
  } catch (const std::exception&) {
    return 0;
  }
}

// What a track holds: its codec, FOURCC, image size, and the unit of its block times.
struct Track {
  int stream = -1;
  AVCodecID codec = AV_CODEC_ID_NONE;
  uint32_t tag = 0;
  int width = 0, height = 0;
  AVRational time_base{1, 1000000};
};

// One colour block as BGR: a JPEG, or raw NV12, YUY2 or BGRA.
cv::Mat DecodeColor(const Track& track, const std::vector<uint8_t>& data,
                    const std::string& where) {
  const int w = track.width, h = track.height;
  cv::Mat bgr;
  if (track.codec == AV_CODEC_ID_MJPEG) {
    bgr = cv::imdecode(data, cv::IMREAD_COLOR);
    if (bgr.empty()) throw InputError(where, "colour frame is not a decodable JPEG");
    if (bgr.cols != w || bgr.rows != h)
      throw InputError(where, "colour JPEG of " + std::to_string(bgr.cols) + "x" +
                                  std::to_string(bgr.rows) + " in a " + std::to_string(w) + "x" +
                                  std::to_string(h) + " track");
    return bgr;
  }
  const size_t pixels = static_cast<size_t>(w) * h;
  const uint32_t tag = track.tag;
  auto raw = [&](int rows, int type, size_t bytes, int conversion) {
    if (data.size() != bytes)
      throw InputError(where, "colour frame of " + std::to_string(data.size()) + " bytes; " +
                                  std::to_string(bytes) + " expected");
    cv::cvtColor(cv::Mat(rows, w, type, const_cast<uint8_t*>(data.data())), bgr, conversion);
    return bgr;
  };
  if (tag == FourCc('N', 'V', '1', '2')) return raw(h * 3 / 2, CV_8UC1, pixels * 3 / 2,
                                                    cv::COLOR_YUV2BGR_NV12);
  if (tag == FourCc('Y', 'U', 'Y', '2')) return raw(h, CV_8UC2, pixels * 2, cv::COLOR_YUV2BGR_YUY2);
  if (track.codec == AV_CODEC_ID_RAWVIDEO && (tag == 0 || tag == FourCc('B', 'G', 'R', 'A')))
    return raw(h, CV_8UC4, pixels * 4, cv::COLOR_BGRA2BGR);
  throw InputError(where, std::string("colour codec ") + avcodec_get_name(track.codec) +
                              " is not supported (MJPG, NV12, YUY2 or BGRA)");
}

}  // namespace

// A recording read in two passes: the block times of both tracks first (to pair depth and colour,
// count the frames and find a truncated file), then the blocks, in file order, as Next() asks.
class AzureKinectMkvSource : public FrameSource {
 public:
  AzureKinectMkvSource(const std::string& path, const FrameSourceOptions& options)
      : path_(path), options_(options) {
    {
      OpenedFile file(path_, &messages_);
      ReadLayout(file.context);
      ReadTimes(file.context);
    }
    pairs_ = PairRecordedStreams(depth_s_, color_s_, options_.max_association_dt_s, path_);
    depth_wanted_.assign(depth_s_.size(), false);
    color_wanted_.assign(color_s_.size(), false);
    for (const auto& [d, c] : pairs_) depth_wanted_[d] = color_wanted_[c] = true;
    file_ = std::make_unique<OpenedFile>(path_, &messages_);
  }

  std::string Kind() const override { return "azure_kinect_mkv"; }
  std::string Input() const override { return path_; }
  const CameraFile& camera_file() const override { return camera_; }
  DepthConvention depth_convention() const override { return DepthConvention::Millimetres(); }
  std::optional<int> FrameCount() const override { return static_cast<int>(pairs_.size()); }
  bool Next(RgbdFrame* frame) override;

 private:
  void ReadLayout(AVFormatContext* context);
  void ReadTimes(AVFormatContext* context);
  // Reads the next block; false at the end of the file. Throws on damage.
  bool ReadBlock(AVFormatContext* context, AVPacket* packet, const std::string& where);
  int64_t DeviceMicroseconds(const AVPacket& packet) const {
    const Track& t = packet.stream_index == depth_.stream ? depth_ : color_;
    return start_offset_us_ + av_rescale_q(packet.pts, t.time_base, AVRational{1, 1000000});
  }
  std::string TimeText(int64_t us) const {
    char text[64];
    std::snprintf(text, sizeof(text), "%lld.%06lld", static_cast<long long>(us / 1000000),
                  static_cast<long long>(us % 1000000));
    return text;
  }

  std::string path_;
  FrameSourceOptions options_;
  std::vector<std::string> messages_;
  CameraFile camera_;
  Track depth_, color_;
  int64_t start_offset_us_ = 0;
  std::vector<double> depth_s_, color_s_;
  std::vector<int64_t> depth_us_;
  std::vector<std::pair<size_t, size_t>> pairs_;
  std::vector<bool> depth_wanted_, color_wanted_;
  std::unique_ptr<OpenedFile> file_;
  size_t next_pair_ = 0, depth_seen_ = 0, color_seen_ = 0;
  std::map<size_t, std::vector<uint8_t>> depth_pending_, color_pending_;
};

void AzureKinectMkvSource::ReadLayout(AVFormatContext* context) {
  for (unsigned i = 0; i < context->nb_streams; ++i) {
    const AVStream* s = context->streams[i];
    const std::string title = Tag(s->metadata, "title");
    if (title != "DEPTH" && title != "COLOR") continue;
    Track& t = title == "DEPTH" ? depth_ : color_;
    t = {static_cast<int>(i), s->codecpar->codec_id, s->codecpar->codec_tag, s->codecpar->width,
         s->codecpar->height, s->time_base};
  }
  if (depth_.stream < 0) throw InputError(path_, "no DEPTH track (not an Azure Kinect recording)");
  if (color_.stream < 0) throw InputError(path_, "no COLOR track (recorded without colour)");
  const AVStream* depth = context->streams[depth_.stream];
  const AVStream* color = context->streams[color_.stream];
  if (depth_.codec != AV_CODEC_ID_RAWVIDEO || depth_.tag != FourCc('b', '1', '6', 'g'))
    throw InputError(path_, std::string("DEPTH track: codec ") + avcodec_get_name(depth_.codec) +
                                " is not the b16g 16-bit depth of a k4a recording");
  std::string depth_mode = Tag(depth->metadata, "K4A_DEPTH_MODE");
  if (depth_mode.empty()) depth_mode = Tag(context->metadata, "K4A_DEPTH_MODE");
  const std::string color_mode = Tag(color->metadata, "K4A_COLOR_MODE");
  const std::optional<AzureKinectMode> mode = AzureKinectDepthMode(depth_mode);
  if (mode && (mode->width != depth_.width || mode->height != depth_.height))
    throw InputError(path_, "DEPTH track of " + std::to_string(depth_.width) + "x" +
                                std::to_string(depth_.height) + " in mode " + depth_mode);
  const int color_height = ColorModeHeight(color_mode);
  if (color_height != color_.height)
    throw InputError(path_, "COLOR track of " + std::to_string(color_.height) +
                                " rows in mode \"" + color_mode + "\"");
  const std::string start = Tag(context->metadata, "K4A_START_OFFSET_NS");
  try {
    start_offset_us_ = start.empty() ? 0 : std::stoll(start) / 1000;
  } catch (const std::exception&) {
    throw InputError(path_, "K4A_START_OFFSET_NS \"" + start + "\" is not a number");
  }
  if (!options_.camera_file.empty()) {
    camera_ = LoadCameraFile(options_.camera_file);
    return;
  }
  for (unsigned i = 0; i < context->nb_streams; ++i) {
    const AVStream* s = context->streams[i];
    if (s->codecpar->codec_type != AVMEDIA_TYPE_ATTACHMENT ||
        Tag(s->metadata, "filename") != "calibration.json")
      continue;
    const std::string text(reinterpret_cast<const char*>(s->codecpar->extradata),
                           static_cast<size_t>(std::max(0, s->codecpar->extradata_size)));
    camera_ = AzureKinectCalibration(text, depth_mode, color_height, path_);
    return;
  }
  throw InputError(path_, "no calibration.json attachment (pass --camera FILE)");
}

bool AzureKinectMkvSource::ReadBlock(AVFormatContext* context, AVPacket* packet,
                                     const std::string& where) {
  CollectAvMessages collect(&messages_);
  messages_.clear();
  const int status = av_read_frame(context, packet);
  if (!messages_.empty())
    throw InputError(where, "damaged Matroska file: " + messages_.front());
  if (status == AVERROR_EOF) return false;
  if (status < 0) throw InputError(where, "unreadable Matroska file: " + AvError(status));
  return true;
}

void AzureKinectMkvSource::ReadTimes(AVFormatContext* context) {
  AVPacket* packet = av_packet_alloc();
  int64_t last_us = 0;
  try {
    while (ReadBlock(context, packet, path_)) {
      if (packet->stream_index == depth_.stream || packet->stream_index == color_.stream) {
        if (packet->pts == AV_NOPTS_VALUE) throw InputError(path_, "a block without a time");
        const int64_t us = DeviceMicroseconds(*packet);
        last_us = std::max(last_us, us);
        (packet->stream_index == depth_.stream ? depth_s_ : color_s_).push_back(us * 1e-6);
        if (packet->stream_index == depth_.stream) depth_us_.push_back(us);
      }
      av_packet_unref(packet);
    }
  } catch (...) {
    av_packet_free(&packet);
    throw;
  }
  av_packet_free(&packet);
  // A file cut short reads to its end without an error; its header still states the duration.
  // k4arecorder's duration ends at the last block of any track (IMU samples run a frame ahead).
  if (context->duration != AV_NOPTS_VALUE && depth_us_.size() >= 1) {
    const double period_s =
        depth_s_.size() > 1 ? (depth_s_.back() - depth_s_.front()) / (depth_s_.size() - 1) : 0.1;
    const double missing_s = context->duration * 1e-6 - (last_us - start_offset_us_) * 1e-6;
    if (missing_s > 2 * period_s + 0.05) {
      char text[160];
      std::snprintf(text, sizeof(text),
                    "truncated: its blocks end %.3f s into a recording of %.3f s",
                    (last_us - start_offset_us_) * 1e-6, context->duration * 1e-6);
      throw InputError(path_, text);
    }
  }
}

bool AzureKinectMkvSource::Next(RgbdFrame* frame) {
  if (next_pair_ >= pairs_.size()) return false;
  const auto [d, c] = pairs_[next_pair_];
  const std::string where =
      path_ + " frame " + std::to_string(next_pair_) + " (depth time " + TimeText(depth_us_[d]) +
      ")";
  AVPacket* packet = av_packet_alloc();
  try {
    while (!depth_pending_.count(d) || (options_.load_color && !color_pending_.count(c))) {
      if (!ReadBlock(file_->context, packet, where))
        throw InputError(where, "the file ended before this frame's images");
      const bool depth = packet->stream_index == depth_.stream;
      if (depth || packet->stream_index == color_.stream) {
        const size_t index = depth ? depth_seen_++ : color_seen_++;
        const std::vector<bool>& wanted = depth ? depth_wanted_ : color_wanted_;
        if (index >= wanted.size())
          throw InputError(where, "more blocks than when the file was opened");
        if (wanted[index] && (depth || options_.load_color))
          (depth ? depth_pending_ : color_pending_)[index].assign(packet->data,
                                                                  packet->data + packet->size);
      }
      av_packet_unref(packet);
    }
  } catch (...) {
    av_packet_free(&packet);
    throw;
  }
  av_packet_free(&packet);
  RgbdFrame f;
  f.index = static_cast<int>(next_pair_);
  f.timestamp = depth_s_[d];
  f.timestamp_text = TimeText(depth_us_[d]);
  f.color_timestamp = color_s_[c];
  std::vector<uint8_t>& bytes = depth_pending_[d];
  const size_t expected = static_cast<size_t>(depth_.width) * depth_.height * 2;
  if (bytes.size() != expected)
    throw InputError(where, "depth frame of " + std::to_string(bytes.size()) + " bytes; " +
                                std::to_string(expected) + " expected");
  cv::Mat raw(depth_.height, depth_.width, CV_16UC1);
  for (size_t i = 0; i < expected / 2; ++i)  // big-endian millimetres
    raw.ptr<uint16_t>()[i] = static_cast<uint16_t>(bytes[2 * i] << 8 | bytes[2 * i + 1]);
  depth_pending_.erase(d);
  ProcessRawDepth(raw, where, camera_, DepthConvention::Millimetres(), options_, &f);
  if (options_.load_color) {
    f.color = DecodeColor(color_, color_pending_[c], where);
    color_pending_.erase(c);
  }
  *frame = std::move(f);
  ++next_pair_;
  return true;
}

bool AzureKinectMkvSupported() { return true; }

std::unique_ptr<FrameSource> OpenAzureKinectMkv(const std::string& path,
                                                const FrameSourceOptions& options) {
  return std::make_unique<AzureKinectMkvSource>(path, options);
}

#else

bool AzureKinectMkvSupported() { return false; }

std::unique_ptr<FrameSource> OpenAzureKinectMkv(const std::string& path,
                                                const FrameSourceOptions&) {
  throw InputError(path,
                   "this build reads no .mkv files (built without libavformat-dev; `make deps` "
                   "installs it)");
}

#endif

}  // namespace gf
