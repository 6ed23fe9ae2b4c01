#include "acquisition/run_layout.h"

#include <filesystem>

namespace gf {

const char* RunLayout::ImageName(KeyframeImage image) {
  switch (image) {
    case KeyframeImage::kHoleMask: return "hole_mask";
    case KeyframeImage::kDepthFilled: return "depth_filled";
    case KeyframeImage::kFillConfidence: return "fill_confidence";
    case KeyframeImage::kFillOverlay: return "fill_overlay";
    case KeyframeImage::kColor: return "color";
    case KeyframeImage::kModelFill: return "model_fill";
    case KeyframeImage::kGlassMask: return "glass_mask";
  }
  return "unknown";
}

std::string RunLayout::Keyframe(const std::string& name, KeyframeImage image) {
  return std::string(kKeyframes) + "/" + name + "." + ImageName(image) + ".png";
}

std::string RunLayout::KeyframeOf(const std::string& file_name, KeyframeImage image) {
  const std::string suffix = std::string(".") + ImageName(image) + ".png";
  if (file_name.size() <= suffix.size() ||
      file_name.compare(file_name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return "";
  return file_name.substr(0, file_name.size() - suffix.size());
}

std::string RunLayout::Undistorted(const std::string& relative) {
  return "undistorted/" + relative;
}

std::string RunLayout::Path(const std::string& relative) const {
  return (std::filesystem::path(dir_) / relative).string();
}

std::string RunLayout::Path(const std::string& name, KeyframeImage image) const {
  return Path(Keyframe(name, image));
}

std::string RunLayout::Rendering(bool with_fill, const std::string& view) {
  return std::string(with_fill ? kWithFill : kWithoutFill) + "_" + view + ".png";
}

RunLayout RunLayout::Map(bool with_fill) const {
  return RunLayout(Path(with_fill ? kWithFill : kWithoutFill));
}

}  // namespace gf
