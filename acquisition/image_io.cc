#include "acquisition/image_io.h"

#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace gf {
namespace {

void RequireFile(const std::string& path) {
  if (!IsRegularFile(path)) throw InputError(path, "file not found");
}

// Reads the next header token of a Netpbm file, skipping whitespace and # comments.
bool NextToken(std::istream& in, std::string* token) {
  token->clear();
  int c;
  while ((c = in.get()) != EOF) {
    if (c == '#') {
      while ((c = in.get()) != EOF && c != '\n') {
      }
      continue;
    }
    if (!std::isspace(c)) break;
  }
  if (c == EOF) return false;
  do {
    token->push_back(static_cast<char>(c));
  } while ((c = in.get()) != EOF && !std::isspace(c));
  return true;  // the single whitespace after maxval has been consumed
}

const char* DepthTypeName(int type) {
  switch (CV_MAT_DEPTH(type)) {
    case CV_8U:
      return "8-bit";
    case CV_16U:
      return "16-bit";
    case CV_32F:
      return "32-bit float";
    default:
      return "unsupported";
  }
}

uint32_t BigEndian(const unsigned char* p, int bytes) {
  uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// JPEG: the frame header (a SOF marker: baseline, progressive, lossless ...) holds the size.
std::optional<cv::Size> JpegSize(std::istream& in) {
  unsigned char b[8];
  while (in.read(reinterpret_cast<char*>(b), 2)) {
    if (b[0] != 0xFF) return std::nullopt;
    const int marker = b[1];
    if (marker == 0xFF) {  // fill byte: the marker follows
      in.unget();
      continue;
    }
    if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) continue;
    if (!in.read(reinterpret_cast<char*>(b), 2)) return std::nullopt;
    const uint32_t length = BigEndian(b, 2);
    if (length < 2) return std::nullopt;
    const bool frame =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame) {
      if (!in.read(reinterpret_cast<char*>(b), 5)) return std::nullopt;
      return cv::Size(static_cast<int>(BigEndian(b + 3, 2)), static_cast<int>(BigEndian(b + 1, 2)));
    }
    in.seekg(length - 2, std::ios::cur);
  }
  return std::nullopt;
}

}  // namespace

bool HasExtension(const std::string& path, const std::string& ext) {
  if (path.size() < ext.size()) return false;
  std::string tail = path.substr(path.size() - ext.size());
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return tail == ext;
}

std::optional<cv::Size> ReadImageSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[24];
  if (!in.read(reinterpret_cast<char*>(head), 2)) return std::nullopt;
  if (head[0] == 0xFF && head[1] == 0xD8) {
    in.seekg(0);
    return JpegSize(in);
  }
  if (head[0] == 'P' && head[1] >= '1' && head[1] <= '6') {  // Netpbm: "P5 <width> <height> ..."
    std::string w, h;
    if (!NextToken(in, &w) || !NextToken(in, &h)) return std::nullopt;
    try {
      size_t used_w = 0, used_h = 0;
      const int width = std::stoi(w, &used_w), height = std::stoi(h, &used_h);
      if (used_w != w.size() || used_h != h.size()) return std::nullopt;
      return cv::Size(width, height);
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  // PNG: the 8-byte signature, then the IHDR chunk (length, "IHDR", width, height).
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (!in.read(reinterpret_cast<char*>(head) + 2, 22) || std::memcmp(head, kPng, 8) != 0 ||
      std::memcmp(head + 12, "IHDR", 4) != 0)
    return std::nullopt;
  const uint32_t width = BigEndian(head + 16, 4), height = BigEndian(head + 20, 4);
  if (width > static_cast<uint32_t>(INT32_MAX) || height > static_cast<uint32_t>(INT32_MAX))
    return std::nullopt;
  return cv::Size(static_cast<int>(width), static_cast<int>(height));
}

cv::Mat ReadColorImage(const std::string& path) {
  RequireFile(path);
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) throw InputError(path, "cannot decode image (corrupt or unsupported format)");
  if (image.depth() != CV_8U)
    throw InputError(
        path, std::string("colour image is ") + DepthTypeName(image.type()) + ", expected 8-bit");
  if (image.channels() == 1)
    cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  else if (image.channels() == 4)
    cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  else if (image.channels() != 3)
    throw InputError(path, "colour image must have 1, 3 or 4 channels");
  return image;
}

cv::Mat ReadDepthImage(const std::string& path) {
  RequireFile(path);
  if (HasExtension(path, ".pgm")) return ReadPgm16(path);
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty())
    throw InputError(path, "cannot decode depth image (corrupt or unsupported format)");
  if (image.channels() != 1)
    throw InputError(
        path, "depth image has " + std::to_string(image.channels()) + " channels, expected 1");
  if (image.depth() != CV_16U)
    throw InputError(
        path, std::string("depth image is ") + DepthTypeName(image.type()) + ", expected 16-bit");
  return image;
}

cv::Mat ReadPgm16(const std::string& path, PgmByteOrder order) {
  RequireFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open for reading");
  std::string magic, w, h, maxval;
  if (!NextToken(in, &magic) || magic != "P5")
    throw InputError(path, "not a binary PGM (expected magic P5)");
  if (!NextToken(in, &w) || !NextToken(in, &h) || !NextToken(in, &maxval))
    throw InputError(path, "truncated PGM header");
  int width = 0, height = 0, max_value = 0;
  try {
    width = std::stoi(w);
    height = std::stoi(h);
    max_value = std::stoi(maxval);
  } catch (const std::exception&) {
    throw InputError(path, "malformed PGM header");
  }
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw InputError(path, "implausible PGM size " + w + "x" + h);
  if (max_value <= 255)
    throw InputError(path, "depth PGM is 8-bit (maxval " + maxval + "), expected 16-bit");
  if (max_value > 65535) throw InputError(path, "PGM maxval " + maxval + " out of range");
  const size_t count = static_cast<size_t>(width) * height;
  std::vector<uint8_t> bytes(count * 2);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<size_t>(in.gcount()) != bytes.size())
    throw InputError(path, "truncated PGM: expected " + std::to_string(bytes.size()) +
                               " bytes of pixels, found " + std::to_string(in.gcount()));
  if (order == PgmByteOrder::kAuto) {
    size_t big_over = 0, little_over = 0;
    for (size_t i = 0; i < count; ++i) {
      if (((bytes[2 * i] << 8) | bytes[2 * i + 1]) > 2047) ++big_over;
      if (((bytes[2 * i + 1] << 8) | bytes[2 * i]) > 2047) ++little_over;
    }
    order =
        (little_over == 0 && big_over > 0) ? PgmByteOrder::kLittleEndian : PgmByteOrder::kBigEndian;
  }
  cv::Mat image(height, width, CV_16UC1);
  uint16_t* out = image.ptr<uint16_t>();
  for (size_t i = 0; i < count; ++i) {
    const uint8_t a = bytes[2 * i], b = bytes[2 * i + 1];
    out[i] = order == PgmByteOrder::kBigEndian ? static_cast<uint16_t>((a << 8) | b)
                                               : static_cast<uint16_t>((b << 8) | a);
  }
  return image;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    bool ok = false;
    try {
      ok = cv::imwrite(temporary, image);
    } catch (const cv::Exception& e) {
      throw InputError(path, std::string("cannot encode image: ") + e.what());
    }
    if (!ok) throw InputError(path, "cannot write image");
  });
}

}  // namespace gf
