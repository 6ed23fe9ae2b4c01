// Reading and writing the image files RGB-D datasets use, with one-line errors naming the file.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace gf {

// 8-bit colour image as BGR (CV_8UC3); grey images are expanded. Throws InputError when the file is
// missing or cannot be decoded.
cv::Mat ReadColorImage(const std::string& path);

// 16-bit single-channel depth image (PNG or PGM) as CV_16UC1. Throws InputError when the file is
// missing, cannot be decoded, or is not 16-bit single-channel (e.g. an 8-bit PNG).
cv::Mat ReadDepthImage(const std::string& path);

// An image's size read from its header alone (PNG, JPEG, PGM/PPM), without decoding or allocating
// its pixels; std::nullopt for another format or a header that cannot be read (decoding the file
// then tells what is wrong with it).
std::optional<cv::Size> ReadImageSize(const std::string& path);

// Binary PGM (P5) with maxval > 255. The Netpbm standard says big-endian, but some tools (the NYU
// Depth raw dumps, libfreenect's fakenect) write little-endian. kAuto picks the byte order whose
// values fit in 11 bits (Kinect raw disparity <= 2047) when exactly one of them does, otherwise
// big-endian as the standard says.
enum class PgmByteOrder { kAuto, kBigEndian, kLittleEndian };
cv::Mat ReadPgm16(const std::string& path, PgmByteOrder order = PgmByteOrder::kAuto);

// Whether path ends in ext (".png", ".xml.gz"; ext in lower case), whatever the case of path.
bool HasExtension(const std::string& path, const std::string& ext);

// Atomic image writers (temporary name, then rename); throw InputError when encoding fails.
void WriteImage(const std::string& path, const cv::Mat& image);

}  // namespace gf
