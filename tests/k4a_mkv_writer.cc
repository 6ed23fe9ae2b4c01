// K4aMkvWriter: FFmpeg's Matroska muxer, then an in-place patch to k4arecorder's layout.
//
// The muxer is used with:
//  - allow_raw_vfw=1: both video tracks are muxed as raw video, which it writes as
//    V_MS/VFW/FOURCC with a BITMAPINFOHEADER (MJPEG would become V_MJPEG instead);
//  - write_crc32=0: no CRC-32 elements, so the header can be changed in place afterwards;
//  - bitexact: no random UIDs or dates, so the same frames give the same bytes.
// It writes FOURCC 0 and a negative biHeight for raw video and ticks of 1 ms. Block times are
// therefore fed as microseconds in the muxer's millisecond ticks, and after the trailer the file
// is patched: TimestampScale 1000000 -> 1000 ns (same element size), each BITMAPINFOHEADER's
// biHeight, biBitCount and biCompression, and the per-track DURATION tags the muxer adds (text in
// its ticks, so 1000 times too long) divided by 1000. Offsets come from walking the EBML
// elements, not from searching bytes.
#include "tests/k4a_mkv_writer.h"

extern "C" {
#include <libavformat/avformat.h>
#include <libavutil/avutil.h>
}

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

namespace gf::testing {
namespace {

std::string AvErrorText(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(code, text, sizeof(text));
  return text;
}

// Throws std::runtime_error naming the file and the call when a libav call failed (code < 0).
void CheckAv(int code, const std::string& path, const char* call) {
  if (code < 0) throw std::runtime_error(path + ": " + call + ": " + AvErrorText(code));
}

constexpr uint32_t FourCc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(static_cast<uint8_t>(a)) |
         static_cast<uint32_t>(static_cast<uint8_t>(b)) << 8 |
         static_cast<uint32_t>(static_cast<uint8_t>(c)) << 16 |
         static_cast<uint32_t>(static_cast<uint8_t>(d)) << 24;
}

cv::Size DepthModeSize(const std::string& mode) {
  static const std::map<std::string, cv::Size> sizes = {{"NFOV_UNBINNED", {640, 576}},
                                                        {"NFOV_2X2BINNED", {320, 288}},
                                                        {"WFOV_UNBINNED", {1024, 1024}},
                                                        {"WFOV_2X2BINNED", {512, 512}}};
  const auto it = sizes.find(mode);
  if (it == sizes.end()) throw std::invalid_argument("K4aMkvWriter: unknown depth mode " + mode);
  return it->second;
}

cv::Size ColorModeSize(int height) {
  static const std::map<int, cv::Size> sizes = {{720, {1280, 720}},   {1080, {1920, 1080}},
                                                {1440, {2560, 1440}}, {1536, {2048, 1536}},
                                                {2160, {3840, 2160}}, {3072, {4096, 3072}}};
  const auto it = sizes.find(height);
  if (it == sizes.end())
    throw std::invalid_argument("K4aMkvWriter: no colour mode of height " +
                                std::to_string(height));
  return it->second;
}

// ----------------------------------------------------------------------------- EBML patching

// EBML element IDs (with their length marker, as the Matroska specification lists them).
constexpr uint32_t kSegmentId = 0x18538067;
constexpr uint32_t kInfoId = 0x1549A966, kTimestampScaleId = 0x2AD7B1;
constexpr uint32_t kTracksId = 0x1654AE6B, kTrackEntryId = 0xAE, kNameId = 0x536E;
constexpr uint32_t kCodecId = 0x86, kCodecPrivateId = 0x63A2;
constexpr uint32_t kTagsId = 0x1254C367, kTagId = 0x7373, kSimpleTagId = 0x67C8;
constexpr uint32_t kTagNameId = 0x45A3, kTagStringId = 0x4487;

// An element: where its data lies in the file. Offsets and sizes in bytes.
struct EbmlElement {
  uint32_t id = 0;
  int64_t data_pos = 0;
  int64_t size = 0;
  int64_t End() const { return data_pos + size; }
};

// A finished Matroska file opened for reading and same-size overwrites.
class EbmlFile {
 public:
  explicit EbmlFile(const std::string& path)
      : path_(path), file_(path, std::ios::in | std::ios::out | std::ios::binary) {
    if (!file_) throw std::runtime_error(path + ": cannot open the muxed file to patch it");
    file_.seekg(0, std::ios::end);
    size_ = file_.tellg();
  }

  EbmlElement Whole() const { return {0, 0, size_}; }

  // The elements inside `parent`'s data, in order.
  std::vector<EbmlElement> Children(const EbmlElement& parent) {
    std::vector<EbmlElement> children;
    for (int64_t pos = parent.data_pos; pos < parent.End();) {
      EbmlElement e;
      int id_length = 0, size_length = 0;
      e.id = static_cast<uint32_t>(ReadVint(pos, true, &id_length));
      e.size = static_cast<int64_t>(ReadVint(pos + id_length, false, &size_length));
      e.data_pos = pos + id_length + size_length;
      if (e.End() > parent.End()) Fail("an element overruns its parent");
      children.push_back(e);
      pos = e.End();
    }
    return children;
  }

  std::vector<uint8_t> Read(const EbmlElement& e) {
    std::vector<uint8_t> data(static_cast<size_t>(e.size));
    file_.seekg(e.data_pos);
    file_.read(reinterpret_cast<char*>(data.data()), e.size);
    if (!file_) Fail("read failed");
    return data;
  }

  void Overwrite(const EbmlElement& e, const std::vector<uint8_t>& data) {
    if (static_cast<int64_t>(data.size()) != e.size) Fail("patch of a different size");
    file_.seekp(e.data_pos);
    file_.write(reinterpret_cast<const char*>(data.data()), e.size);
    file_.flush();
    if (!file_) Fail("write failed");
  }

  [[noreturn]] void Fail(const std::string& what) const {
    throw std::runtime_error(path_ + ": patching the muxed file: " + what);
  }

 private:
  // An EBML variable-length integer at `pos`: the leading zeros of its first byte give its length
  // in bytes (1-8). IDs keep that length marker; sizes drop it. All-ones sizes (unknown) fail.
  uint64_t ReadVint(int64_t pos, bool keep_marker, int* length) {
    uint8_t bytes[8] = {0};
    file_.seekg(pos);
    file_.read(reinterpret_cast<char*>(bytes), 1);
    if (!file_ || bytes[0] == 0) Fail("bad element header");
    int n = 1;
    while (!(bytes[0] & (0x80 >> (n - 1)))) ++n;
    file_.read(reinterpret_cast<char*>(bytes + 1), n - 1);
    if (!file_) Fail("truncated element header");
    uint64_t value = keep_marker ? bytes[0] : bytes[0] & (0xFF >> n);
    bool all_ones = value == (0xFFu >> n);
    for (int k = 1; k < n; ++k) {
      value = value << 8 | bytes[k];
      all_ones = all_ones && bytes[k] == 0xFF;
    }
    if (!keep_marker && all_ones) Fail("element of unknown size");
    *length = n;
    return value;
  }

  std::string path_;
  std::fstream file_;
  int64_t size_ = 0;
};

const EbmlElement* FindChild(const std::vector<EbmlElement>& children, uint32_t id) {
  for (const EbmlElement& e : children)
    if (e.id == id) return &e;
  return nullptr;
}

std::string ReadString(EbmlFile& file, const EbmlElement* e) {
  if (!e) return {};
  const std::vector<uint8_t> data = file.Read(*e);
  return std::string(data.begin(), std::find(data.begin(), data.end(), 0));
}

// What a video track's BITMAPINFOHEADER must say (k4arecorder's values).
struct TrackPatch {
  std::string name;        // the track's Name, "COLOR" or "DEPTH"
  cv::Size size;           // pixels
  uint16_t bit_count = 0;  // biBitCount, bits per pixel
  uint32_t compression = 0;  // biCompression, a FOURCC or 0 (BI_RGB)
  bool done = false;
};

void PutLittleEndian(std::vector<uint8_t>* data, size_t offset, uint32_t value, int bytes) {
  for (int k = 0; k < bytes; ++k) (*data)[offset + k] = static_cast<uint8_t>(value >> (8 * k));
}

int32_t GetLittleEndian32(const std::vector<uint8_t>& data, size_t offset) {
  uint32_t value = 0;
  for (int k = 3; k >= 0; --k) value = value << 8 | data[offset + k];
  return static_cast<int32_t>(value);
}

void PatchTrack(EbmlFile& file, const EbmlElement& entry, std::vector<TrackPatch>* patches) {
  const std::vector<EbmlElement> children = file.Children(entry);
  const std::string name = ReadString(file, FindChild(children, kNameId));
  for (TrackPatch& patch : *patches) {
    if (patch.name != name) continue;
    if (ReadString(file, FindChild(children, kCodecId)) != "V_MS/VFW/FOURCC")
      file.Fail("track " + name + " is not V_MS/VFW/FOURCC");
    const EbmlElement* codec_private = FindChild(children, kCodecPrivateId);
    if (!codec_private) file.Fail("track " + name + " has no CodecPrivate");
    // BITMAPINFOHEADER, little-endian: biSize 0, biWidth 4, biHeight 8, biPlanes 12,
    // biBitCount 14, biCompression 16, biSizeImage 20, ... (40 bytes).
    std::vector<uint8_t> header = file.Read(*codec_private);
    if (header.size() < 40 || GetLittleEndian32(header, 0) < 40 ||
        GetLittleEndian32(header, 4) != patch.size.width ||
        std::abs(GetLittleEndian32(header, 8)) != patch.size.height)
      file.Fail("track " + name + " has an unexpected BITMAPINFOHEADER");
    PutLittleEndian(&header, 8, static_cast<uint32_t>(patch.size.height), 4);  // top-down
    PutLittleEndian(&header, 14, patch.bit_count, 2);
    PutLittleEndian(&header, 16, patch.compression, 4);
    file.Overwrite(*codec_private, header);
    patch.done = true;
  }
}

// TimestampScale 1 ms -> 1 us, keeping the element's size (a leading zero byte is valid EBML).
bool PatchTimestampScale(EbmlFile& file, const EbmlElement& info) {
  const std::vector<EbmlElement> children = file.Children(info);
  const EbmlElement* scale = FindChild(children, kTimestampScaleId);
  if (!scale) return false;
  std::vector<uint8_t> data = file.Read(*scale);
  uint64_t value = 0;
  for (uint8_t b : data) value = value << 8 | b;
  if (value != 1000000 || data.size() < 2) file.Fail("unexpected TimestampScale");
  const uint64_t microsecond_ns = 1000;
  for (size_t k = 0; k < data.size(); ++k)
    data[data.size() - 1 - k] = static_cast<uint8_t>(k < 8 ? microsecond_ns >> (8 * k) : 0);
  file.Overwrite(*scale, data);
  return true;
}

// The muxer's DURATION tags ("HH:MM:SS.nnnnnnnnn", written in its millisecond ticks, which hold
// microseconds here) divided by 1000, padded with NULs to the same size.
void PatchDurationTags(EbmlFile& file, const EbmlElement& tags) {
  for (const EbmlElement& tag : file.Children(tags)) {
    if (tag.id != kTagId) continue;
    for (const EbmlElement& simple : file.Children(tag)) {
      if (simple.id != kSimpleTagId) continue;
      const std::vector<EbmlElement> fields = file.Children(simple);
      const EbmlElement* value = FindChild(fields, kTagStringId);
      if (ReadString(file, FindChild(fields, kTagNameId)) != "DURATION" || !value) continue;
      int hours = 0, minutes = 0;
      double seconds = 0;
      if (std::sscanf(ReadString(file, value).c_str(), "%d:%d:%lf", &hours, &minutes, &seconds) != 3)
        file.Fail("unreadable DURATION tag");
      const double true_s = (3600.0 * hours + 60.0 * minutes + seconds) / 1000.0;
      char text[64];
      const int length = std::snprintf(text, sizeof(text), "%02d:%02d:%012.9f",
                                        static_cast<int>(true_s / 3600),
                                        static_cast<int>(true_s / 60) % 60,
                                        true_s - 60.0 * static_cast<int>(true_s / 60));
      if (length < 0 || length > value->size) file.Fail("DURATION tag too short");
      std::vector<uint8_t> data(static_cast<size_t>(value->size), 0);
      std::memcpy(data.data(), text, static_cast<size_t>(length));
      file.Overwrite(*value, data);
    }
  }
}

void PatchToK4aLayout(const std::string& path, std::vector<TrackPatch> patches) {
  EbmlFile file(path);
  const std::vector<EbmlElement> top = file.Children(file.Whole());
  const EbmlElement* segment = FindChild(top, kSegmentId);
  if (!segment) file.Fail("no Segment");
  bool scale_done = false;
  for (const EbmlElement& e : file.Children(*segment)) {
    if (e.id == kInfoId) scale_done = PatchTimestampScale(file, e) || scale_done;
    if (e.id == kTagsId) PatchDurationTags(file, e);
    if (e.id != kTracksId) continue;
    for (const EbmlElement& entry : file.Children(e))
      if (entry.id == kTrackEntryId) PatchTrack(file, entry, &patches);
  }
  if (!scale_done) file.Fail("no TimestampScale");
  for (const TrackPatch& patch : patches)
    if (!patch.done) file.Fail("no track " + patch.name);
}

}  // namespace

// ----------------------------------------------------------------------------- the muxer

struct K4aMkvWriter::Muxer {
  AVFormatContext* context = nullptr;
  AVStream* color = nullptr;
  AVStream* depth = nullptr;
  AVPacket* packet = nullptr;
  std::string path;

  ~Muxer() {
    av_packet_free(&packet);
    if (context) avio_closep(&context->pb);
    avformat_free_context(context);
  }

  AVStream* AddVideo(const char* title, cv::Size size, int bits_per_pixel, const char* mode_tag,
                     const std::string& mode) {
    AVStream* stream = avformat_new_stream(context, nullptr);
    if (!stream) throw std::runtime_error(path + ": avformat_new_stream failed");
    AVCodecParameters* par = stream->codecpar;
    par->codec_type = AVMEDIA_TYPE_VIDEO;
    par->codec_id = AV_CODEC_ID_RAWVIDEO;  // FOURCC 0: muxed as V_MS/VFW/FOURCC, patched later
    par->codec_tag = 0;
    par->bits_per_coded_sample = bits_per_pixel;
    par->width = size.width;
    par->height = size.height;
    stream->time_base = {1, 1000000};  // asked for; the muxer keeps 1/1000
    av_dict_set(&stream->metadata, "title", title, 0);
    av_dict_set(&stream->metadata, mode_tag, mode.c_str(), 0);
    return stream;
  }

  void AddCalibration(const std::string& json) {
    AVStream* stream = avformat_new_stream(context, nullptr);
    if (!stream) throw std::runtime_error(path + ": avformat_new_stream failed");
    AVCodecParameters* par = stream->codecpar;
    par->codec_type = AVMEDIA_TYPE_ATTACHMENT;
    par->codec_id = AV_CODEC_ID_NONE;
    par->extradata = static_cast<uint8_t*>(av_mallocz(json.size() + AV_INPUT_BUFFER_PADDING_SIZE));
    if (!par->extradata) throw std::runtime_error(path + ": out of memory");
    std::memcpy(par->extradata, json.data(), json.size());
    par->extradata_size = static_cast<int>(json.size());
    av_dict_set(&stream->metadata, "filename", "calibration.json", 0);
    av_dict_set(&stream->metadata, "mimetype", "application/octet-stream", 0);
    av_dict_set(&stream->metadata, "K4A_CALIBRATION_FILE", "calibration.json", 0);
  }

  // A block of `size` bytes at block time `time_us` (microseconds); `fill` writes its bytes.
  template <typename Fill>
  void WriteBlock(AVStream* stream, size_t size, int64_t time_us, Fill fill) {
    CheckAv(av_new_packet(packet, static_cast<int>(size)), path, "av_new_packet");
    fill(packet->data);
    packet->stream_index = stream->index;
    packet->pts = packet->dts = time_us;  // in the muxer's 1 ms ticks: see the file comment
    packet->flags |= AV_PKT_FLAG_KEY;
    CheckAv(av_interleaved_write_frame(context, packet), path, "av_interleaved_write_frame");
  }
};

K4aMkvWriter::K4aMkvWriter(const std::string& path, const K4aMkvOptions& options)
    : path_(path), options_(options) {
  depth_size_ = DepthModeSize(options.depth_mode);
  color_size_ = ColorModeSize(options.color_height);
  if (options.color_format != "MJPG" && options.color_format != "BGRA")
    throw std::invalid_argument("K4aMkvWriter: colour format must be MJPG or BGRA, not " +
                                options.color_format);
  if (options.jpeg_quality < 0 || options.jpeg_quality > 100)
    throw std::invalid_argument("K4aMkvWriter: jpeg_quality must be 0-100");
  muxer_ = std::make_unique<Muxer>();
  Muxer& m = *muxer_;
  m.path = path;
  CheckAv(avformat_alloc_output_context2(&m.context, nullptr, "matroska", path.c_str()), path,
          "avformat_alloc_output_context2");
  m.packet = av_packet_alloc();
  if (!m.packet) throw std::runtime_error(path + ": out of memory");
  m.context->flags |= AVFMT_FLAG_BITEXACT;
  av_dict_set(&m.context->metadata, "title", "Azure Kinect", 0);
  av_dict_set(&m.context->metadata, "K4A_START_OFFSET_NS",
              std::to_string(options.start_offset_ns).c_str(), 0);
  av_dict_set(&m.context->metadata, "K4A_DEPTH_DELAY_NS", "0", 0);
  av_dict_set(&m.context->metadata, "K4A_WIRED_SYNC_MODE", "STANDALONE", 0);
  const bool mjpg = options.color_format == "MJPG";
  m.color = m.AddVideo("COLOR", color_size_, mjpg ? 24 : 32, "K4A_COLOR_MODE",
                       options.color_format + "_" + std::to_string(options.color_height) + "P");
  m.depth = m.AddVideo("DEPTH", depth_size_, 16, "K4A_DEPTH_MODE", options.depth_mode);
  if (!options.calibration_json.empty()) m.AddCalibration(options.calibration_json);

  CheckAv(avio_open(&m.context->pb, path.c_str(), AVIO_FLAG_WRITE), path, "avio_open");
  AVDictionary* muxer_options = nullptr;
  av_dict_set(&muxer_options, "allow_raw_vfw", "1", 0);
  av_dict_set(&muxer_options, "write_crc32", "0", 0);
  // The muxer warns "codec rawvideo is not supported by this format" for each VFW track (the
  // FOURCC is patched later): quieten the default log for this call only.
  const int log_level = av_log_get_level();
  av_log_set_level(std::min(log_level, AV_LOG_ERROR));
  const int rc = avformat_write_header(m.context, &muxer_options);
  av_log_set_level(log_level);
  const bool all_used = av_dict_count(muxer_options) == 0;  // the unknown ones are left
  av_dict_free(&muxer_options);
  CheckAv(rc, path, "avformat_write_header");
  if (!all_used) throw std::runtime_error(path + ": the Matroska muxer lacks an option");
  for (const AVStream* stream : {m.color, m.depth})
    if (stream->time_base.num != 1 || stream->time_base.den != 1000)
      throw std::runtime_error(path + ": the Matroska muxer did not keep 1 ms ticks");
}

K4aMkvWriter::~K4aMkvWriter() {
  try {
    Finish();
  } catch (const std::exception&) {
    // A destructor must not throw; call Finish() to see the error.
  }
}

void K4aMkvWriter::Write(const K4aMkvFrame& frame) {
  if (!muxer_) throw std::invalid_argument(path_ + ": Write after Finish");
  if (frame.time_us < 0) throw std::invalid_argument(path_ + ": negative block time");
  const cv::Mat& depth = frame.depth_mm;
  const cv::Mat& color = frame.color_bgr;
  if (depth.empty() && color.empty()) throw std::invalid_argument(path_ + ": empty frame");
  if (!depth.empty() && (depth.type() != CV_16UC1 || depth.size() != depth_size_))
    throw std::invalid_argument(path_ + ": depth must be CV_16UC1 of the depth mode's size");
  if (!color.empty() && (color.type() != CV_8UC3 || color.size() != color_size_))
    throw std::invalid_argument(path_ + ": colour must be CV_8UC3 of the colour mode's size");
  Muxer& m = *muxer_;
  if (!color.empty() && options_.color_format == "MJPG") {
    std::vector<uint8_t> jpeg;
    if (!cv::imencode(".jpg", color, jpeg, {cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality}))
      throw std::runtime_error(path_ + ": JPEG encoding failed");
    m.WriteBlock(m.color, jpeg.size(), frame.time_us,
                 [&](uint8_t* out) { std::memcpy(out, jpeg.data(), jpeg.size()); });
  } else if (!color.empty()) {
    cv::Mat bgra;
    cv::cvtColor(color, bgra, cv::COLOR_BGR2BGRA);  // alpha 255
    const size_t row_bytes = bgra.cols * bgra.elemSize();
    m.WriteBlock(m.color, row_bytes * bgra.rows, frame.time_us, [&](uint8_t* out) {
      for (int v = 0; v < bgra.rows; ++v) std::memcpy(out + v * row_bytes, bgra.ptr(v), row_bytes);
    });
  }
  if (!depth.empty()) {
    // Millimetres as 16-bit big-endian, rows top-down.
    m.WriteBlock(m.depth, depth.total() * 2, frame.time_us, [&](uint8_t* out) {
      for (int v = 0; v < depth.rows; ++v) {
        const uint16_t* row = depth.ptr<uint16_t>(v);
        for (int u = 0; u < depth.cols; ++u, out += 2) {
          out[0] = static_cast<uint8_t>(row[u] >> 8);
          out[1] = static_cast<uint8_t>(row[u] & 0xFF);
        }
      }
    });
  }
}

void K4aMkvWriter::Finish() {
  if (!muxer_) return;
  const std::unique_ptr<Muxer> muxer = std::move(muxer_);
  CheckAv(av_write_trailer(muxer->context), path_, "av_write_trailer");
  CheckAv(avio_closep(&muxer->context->pb), path_, "avio_closep");
  const bool mjpg = options_.color_format == "MJPG";
  PatchToK4aLayout(path_, {{"DEPTH", depth_size_, 16, FourCc('b', '1', '6', 'g')},
                           {"COLOR", color_size_, static_cast<uint16_t>(mjpg ? 24 : 32),
                            mjpg ? FourCc('M', 'J', 'P', 'G') : 0u}});
}

}  // namespace gf::testing
