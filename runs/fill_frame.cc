#include "runs/fill_frame.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/json_text.h"
#include "pipeline/run_sink.h"

namespace gf {
namespace {

// The single-channel float image in `m` (its first channel), holes where not finite or <= 0.
cv::Mat CleanMetres(const std::string& path, const cv::Mat& m) {
  if (m.empty() || (m.depth() != CV_32F && m.depth() != CV_64F))
    throw InputError(path, "holds no float depth image (metres)");
  cv::Mat first;
  cv::extractChannel(m, first, 0);
  first.convertTo(first, CV_32F);
  for (int y = 0; y < first.rows; ++y) {
    float* row = first.ptr<float>(y);
    for (int x = 0; x < first.cols; ++x)
      if (!std::isfinite(row[x]) || row[x] <= 0) row[x] = 0;
  }
  return first;
}

cv::Mat ReadFileStorageDepth(const std::string& path) {
  cv::Mat m;
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) throw InputError(path, "cannot be opened as OpenCV FileStorage");
    cv::FileNode node = fs["depth_image"];
    if (node.empty() && fs.root().isMap() && fs.root().size() > 0) node = *fs.root().begin();
    if (!node.isMap()) throw InputError(path, "holds no float depth image (metres)");
    node >> m;
  } catch (const cv::Exception&) {
    throw InputError(path, "cannot be read as OpenCV FileStorage (.xml, .yml, .json)");
  }
  return CleanMetres(path, m);
}

nlohmann::ordered_json Report(const FillFrameOptions& o, const FillFrameSummary& s) {
  const GlassFrameResult& r = s.result;
  nlohmann::ordered_json regions = nlohmann::ordered_json::array();
  for (const GlassFrameRegion& g : r.regions)
    regions.push_back({{"pixels", g.pixels},
                       {"shaped", g.shaped},
                       {"radius_m", g.radius_m},
                       {"height_m", g.height_m},
                       {"replaced_pixels", g.replaced}});
  return {{"color", o.color_file},
          {"depth", o.depth_file},
          {"camera", o.camera_file},
          {"mask", !o.mask_file.empty() ? o.mask_file
                   : o.boxes.empty()    ? "found"
                                        : "boxes"},
          {"depth_pixels", s.depth_pixels},
          {"support_plane",
           {{"found", r.plane_found},
            {"normal", {r.plane_normal.x(), r.plane_normal.y(), r.plane_normal.z()}},
            {"offset_m", r.plane_offset_m},
            {"ransac_inliers", r.plane_inliers}}},
          {"glass_pixels", cv::countNonZero(r.glass_mask)},
          {"replaced_pixels", r.replaced_pixels},
          {"regions", regions}};
}

// The colour image with the glass found tinted cyan and the pixels given its depth orange (as a
// run's fill_overlay.png shows glass and completed pixels).
cv::Mat Overlay(const cv::Mat& color, const cv::Mat& depth_m, const GlassFrameResult& r) {
  cv::Mat overlay = color.clone();
  TintOverlay(color, r.glass_mask, kGlassTint, &overlay);
  TintOverlay(color, r.depth_filled != depth_m, kCompletedTint, &overlay);
  return overlay;
}

}  // namespace

std::string FillFrameSummary::BriefReport() const { return result.BriefReport(); }

cv::Rect ParseBox(const std::string& text, const std::string& what) {
  int x = 0, y = 0, w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d,%d,%d,%d%c", &x, &y, &w, &h, &tail) != 4 || w <= 0 || h <= 0)
    throw InputError(what, "'" + text + "' is not a box x,y,w,h (pixels, w and h above 0)");
  return cv::Rect(x, y, w, h);
}

cv::Mat ReadMetricDepth(const std::string& path, double depth_scale) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, "no such file");
  if (HasExtension(path, ".exr")) {
    // OpenCV decodes OpenEXR only when this is set before its first EXR read.
    setenv("OPENCV_IO_ENABLE_OPENEXR", "1", 0);
    cv::Mat m;
    try {
      m = cv::imread(path, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      throw InputError(path, "cannot be decoded as OpenEXR");
    }
    return CleanMetres(path, m);
  }
  for (const char* ext :
       {".xml", ".yml", ".yaml", ".json", ".xml.gz", ".yml.gz", ".yaml.gz", ".json.gz"})
    if (HasExtension(path, ext)) return ReadFileStorageDepth(path);
  const cv::Mat raw = ReadDepthImage(path);
  cv::Mat depth_m;
  ConvertDepth(raw, DepthConvention::FromDepthScale(depth_scale), DepthConversionOptions(),
               &depth_m, nullptr);
  return depth_m;
}

FillFrameSummary RunFillFrame(const FillFrameOptions& o) {
  std::string problem;
  if (!o.glass.Check(&problem)) throw InputError("glass settings", problem);
  const CameraFile camera = LoadCameraFile(o.camera_file);
  const cv::Mat depth = ReadMetricDepth(o.depth_file, camera.depth_scale);
  const cv::Size size(camera.camera.width, camera.camera.height);
  if (depth.size() != size)
    throw InputError(o.depth_file, "is " + std::to_string(depth.cols) + "x" +
                                       std::to_string(depth.rows) + ", the camera " +
                                       std::to_string(size.width) + "x" +
                                       std::to_string(size.height));
  const cv::Mat color = ReadColorImage(o.color_file);
  if (color.size() != size) throw InputError(o.color_file, "is not at the camera's size");
  cv::Mat mask;
  if (!o.mask_file.empty() && !o.boxes.empty())
    throw InputError(o.mask_file, "give the glass as a mask or as boxes, not both");
  if (!o.boxes.empty()) mask = GlassRegionsFromBoxes(color, o.boxes);
  if (!o.mask_file.empty()) {
    mask = cv::imread(o.mask_file, cv::IMREAD_GRAYSCALE);
    if (mask.empty()) throw InputError(o.mask_file, "cannot be decoded as an image");
    if (mask.size() != size) throw InputError(o.mask_file, "is not at the camera's size");
  }
  FillFrameSummary s;
  s.depth_pixels = cv::countNonZero(depth > 0);
  s.result = FindGlassInFrame(color, depth, camera.camera, o.glass, mask);
  std::error_code error;
  std::filesystem::create_directories(o.out_dir, error);
  if (!std::filesystem::is_directory(o.out_dir))
    throw InputError(o.out_dir, "cannot be made a folder" +
                                    (error ? " (" + error.message() + ")" : std::string()));
  const std::filesystem::path out(o.out_dir);
  WriteImage((out / "glass_mask.png").string(), s.result.glass_mask);
  WriteImage((out / "depth_filled.png").string(),
             DepthToRaw(s.result.depth_filled, DepthConvention::Millimetres()));
  WriteImage((out / "glass_overlay.png").string(), Overlay(color, depth, s.result));
  WriteTextFileAtomically((out / "fill_frame.json").string(), JsonText(Report(o, s)) + "\n");
  return s;
}

}  // namespace gf
