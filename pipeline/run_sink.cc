#include "pipeline/run_sink.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "acquisition/depth.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/json_text.h"
#include "acquisition/run_layout.h"
#include "surfels/ply.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

cv::Mat ToMillimetres(const cv::Mat& depth_m) {
  cv::Mat mm(depth_m.size(), CV_16UC1);
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const double d = depth_m.at<float>(y, x) * 1000.0;
      mm.at<uint16_t>(y, x) = d > 0 ? static_cast<uint16_t>(std::min(65535.0, std::round(d))) : 0;
    }
  return mm;
}

// A trajectory entry's frame name (KeyframeName) where its stamp is the text read or the index.
std::string PoseName(const StampedPose& pose) {
  return pose.timestamp_text.empty() ? std::to_string(static_cast<long>(pose.timestamp))
                                     : pose.timestamp_text;
}

RunFolder::Options Earlier(bool replace) {
  RunFolder::Options options;
  options.earlier = replace ? RunFolder::kReplace : RunFolder::kRefuse;
  return options;
}

}  // namespace

int CompleteFromModel(const cv::Mat& hole_mask, const MapCompletion& offer, cv::Mat* filled_depth,
                      cv::Mat* confidence, cv::Mat* completed) {
  const cv::Mat& model_depth = offer.depth;
  GF_CHECK(hole_mask.type() == CV_8UC1 && model_depth.type() == CV_32FC1 &&
               filled_depth->type() == CV_32FC1 && hole_mask.size() == model_depth.size() &&
               filled_depth->size() == model_depth.size() &&
               offer.confidence.type() == CV_32FC1 && offer.confidence.size() == model_depth.size(),
           "completion: CV_8U holes, CV_32F depths and confidence of one size");
  // Not in projector shadows: there the far surface is what colour sees, and a fill in front of
  // it in the model is the near surface's fill spread past its edge (the keyframe's own fill
  // tests shadows against both sides; ValidateAndFill).
  *completed = (hole_mask != 0) & (hole_mask != static_cast<uint8_t>(HoleCode::kShadow)) &
               (*filled_depth <= 0) & (model_depth > 0);
  if (offer.occluder_px > 0) {
    // The nearest sensor depth within occluder_px of each pixel (a minimum filter; no sensor
    // depth: infinitely far).
    cv::Mat sensor = filled_depth->clone();
    sensor.setTo(std::numeric_limits<float>::max(), (hole_mask != 0) | (sensor <= 0));
    cv::Mat nearest;
    cv::erode(sensor, nearest,
              cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * offer.occluder_px + 1,
                                                                 2 * offer.occluder_px + 1)));
    *completed &= nearest >= model_depth * (1.0 - offer.occluder_margin);
  }
  model_depth.copyTo(*filled_depth, *completed);
  if (confidence) offer.confidence.copyTo(*confidence, *completed);
  return cv::countNonZero(*completed);
}

void TintOverlay(const cv::Mat& color, const cv::Mat& mask, const cv::Scalar& tint,
                 cv::Mat* overlay) {
  cv::Mat tinted;
  cv::addWeighted(color, 0.5, cv::Mat(color.size(), CV_8UC3, tint), 0.5, 0, tinted);
  tinted.copyTo(*overlay, mask);
}

cv::Mat FillOverlay(const cv::Mat& color, const CarriedFillResult& fill) {
  cv::Mat out = color.clone();
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      cv::Vec3b& p = out.at<cv::Vec3b>(y, x);
      cv::Vec3d tint;
      double w;
      if (fill.fill_mask.at<uint8_t>(y, x)) {
        tint = fill.source.at<uint8_t>(y, x) == static_cast<uint8_t>(DepthSource::kCarried)
                   ? cv::Vec3d(255, 255, 0)
                   : cv::Vec3d(0, 255, 0);
        w = 0.35 + 0.4 * fill.confidence.at<float>(y, x);
      } else if (!(fill.filled_depth.at<float>(y, x) > 0)) {
        tint = {255, 0, 255};
        w = 0.35;
      } else {
        continue;
      }
      for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uint8_t>((1 - w) * p[c] + w * tint[c]);
    }
  return out;
}

FolderRunSink::FolderRunSink(const std::string& out_dir, const RunFolder::Options& options)
    : owned_(std::make_unique<RunFolder>(out_dir, options)),
      folder_(owned_.get()),
      out_dir_(out_dir) {}

FolderRunSink::FolderRunSink(const std::string& out_dir, bool replace)
    : FolderRunSink(out_dir, Earlier(replace)) {}

FolderRunSink::FolderRunSink(RunFolder* folder, const std::string& subfolder)
    : folder_(folder), prefix_(subfolder + "/"), out_dir_(folder->Folder(subfolder)) {}

std::string FolderRunSink::File(const std::string& relative) {
  return folder_->File(prefix_ + relative);
}

void FolderRunSink::WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                                  const CarriedFillResult& fill) {
  // keyframes/ comes with the first keyframe: a run without fill has none.
  auto keyframe = [&](KeyframeImage image) { return File(RunLayout::Keyframe(name, image)); };
  WriteImage(keyframe(KeyframeImage::kHoleMask), frame.hole_mask);
  WriteImage(keyframe(KeyframeImage::kDepthFilled), ToMillimetres(fill.filled_depth));
  if (fill.confidence.type() == CV_32FC1 && fill.fill_mask.type() == CV_8UC1) {
    // The fill's confidence on the filled pixels, 0-255 for 0-1; 0 elsewhere.
    cv::Mat confidence;
    fill.confidence.convertTo(confidence, CV_8U, 255.0);
    confidence.setTo(0, fill.fill_mask == 0);
    WriteImage(keyframe(KeyframeImage::kFillConfidence), confidence);
  }
  const bool has_color = frame.color.type() == CV_8UC3 && frame.color.size() == frame.depth.size();
  if (has_color) {
    WriteImage(keyframe(KeyframeImage::kFillOverlay), FillOverlay(frame.color, fill));
    WriteImage(keyframe(KeyframeImage::kColor), frame.color);  // for colmap-export
  }
  // The pinhole set (undistorted/), colour and depth under the same file name.
  const std::string file = IndexedFileName(frame.index, frame.timestamp_text);
  WriteImage(File(RunLayout::Undistorted("depth/" + file)),
             Undistort(ToMillimetres(fill.filled_depth), cv::INTER_NEAREST));
  if (has_color)
    WriteImage(File(RunLayout::Undistorted("color/" + file)), Undistort(frame.color, cv::INTER_LINEAR));
  std::lock_guard<std::mutex> lock(mutex_);
  keyframes_[frame.index] = {name, file};
}

cv::Mat FolderRunSink::Undistort(const cv::Mat& image, int interpolation) const {
  if (undistort_x_.empty()) return image;
  cv::Mat out;
  cv::remap(image, out, undistort_x_, undistort_y_, interpolation, cv::BORDER_CONSTANT, 0);
  return out;
}

void FolderRunSink::PrepareCompletion(const std::vector<std::string>& names) {
  for (const std::string& name : names)
    for (KeyframeImage image : {KeyframeImage::kGlassMask, KeyframeImage::kModelFill})
      File(RunLayout::Keyframe(name, image));
}

cv::Mat FolderRunSink::KeyframeColor(const std::string& name) const {
  return cv::imread(RunLayout(out_dir_).Path(name, KeyframeImage::kColor), cv::IMREAD_COLOR);
}

int FolderRunSink::CompleteKeyframe(const std::string& name, const MapCompletion& offer) {
  std::string pinhole_file;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [index, written] : keyframes_)
      if (written.name == name) pinhole_file = written.pinhole_file;
  }
  if (pinhole_file.empty()) throw std::out_of_range("no keyframe " + name + " written");
  const RunLayout run(out_dir_);
  const cv::Mat mm = cv::imread(run.Path(name, KeyframeImage::kDepthFilled), cv::IMREAD_UNCHANGED);
  const cv::Mat holes = cv::imread(run.Path(name, KeyframeImage::kHoleMask), cv::IMREAD_UNCHANGED);
  cv::Mat confidence_8u =
      cv::imread(run.Path(name, KeyframeImage::kFillConfidence), cv::IMREAD_UNCHANGED);
  if (mm.type() != CV_16UC1 || holes.type() != CV_8UC1 || mm.size() != holes.size() ||
      mm.size() != offer.depth.size())
    throw InputError(run.Path(name, KeyframeImage::kDepthFilled),
                     "cannot be read back with its hole mask at the camera's size");
  if (confidence_8u.type() != CV_8UC1 || confidence_8u.size() != mm.size())
    confidence_8u = cv::Mat::zeros(mm.size(), CV_8UC1);  // a keyframe whose fill failed has none
  cv::Mat filled, completed, confidence;
  mm.convertTo(filled, CV_32F, 0.001);
  confidence_8u.convertTo(confidence, CV_32F, 1.0 / 255);
  const bool glass = !offer.glass.empty() && offer.glass.size() == mm.size();
  if (glass) WriteImage(File(RunLayout::Keyframe(name, KeyframeImage::kGlassMask)), offer.glass);
  const int pixels = CompleteFromModel(holes, offer, &filled, &confidence, &completed);
  const bool any_glass = glass && cv::countNonZero(offer.glass) > 0;
  if (pixels == 0 && !any_glass) return 0;
  // The overlay shows the completed pixels orange (they were magenta: holes left empty) and the
  // glass cyan.
  const cv::Mat color = cv::imread(run.Path(name, KeyframeImage::kColor), cv::IMREAD_COLOR);
  cv::Mat overlay = cv::imread(run.Path(name, KeyframeImage::kFillOverlay), cv::IMREAD_COLOR);
  if (!color.empty() && color.size() == overlay.size() && color.size() == completed.size()) {
    TintOverlay(color, completed, kCompletedTint, &overlay);
    if (any_glass) TintOverlay(color, offer.glass, kGlassTint, &overlay);
    WriteImage(File(RunLayout::Keyframe(name, KeyframeImage::kFillOverlay)), overlay);
  }
  if (pixels == 0) return 0;
  // depth_filled.png (what users and the figures read) last: when an earlier write fails it stays
  // as the keyframe's fill left it, and the warning says the keyframe was not completed.
  const cv::Mat completed_mm = ToMillimetres(filled);
  WriteImage(File(RunLayout::Keyframe(name, KeyframeImage::kModelFill)), completed);
  confidence.convertTo(confidence_8u, CV_8U, 255.0);
  WriteImage(File(RunLayout::Keyframe(name, KeyframeImage::kFillConfidence)), confidence_8u);
  WriteImage(File(RunLayout::Undistorted("depth/" + pinhole_file)),
             Undistort(completed_mm, cv::INTER_NEAREST));
  WriteImage(File(RunLayout::Keyframe(name, KeyframeImage::kDepthFilled)), completed_mm);
  return pixels;
}

void FolderRunSink::WriteTrajectory(const Trajectory& trajectory) {
  WriteTumTrajectory(File(RunLayout::kTrajectory), trajectory);
  std::map<std::string, SE3> poses;
  for (const StampedPose& p : trajectory) poses[PoseName(p)] = p.world_from_camera;
  Trajectory keyframes;  // undistorted/trajectory.log: entry k is the k-th file, by name
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [index, written] : keyframes_) {
    const auto pose = poses.find(written.name);
    if (pose == poses.end()) continue;  // a keyframe whose pose the run did not keep
    keyframes.push_back({static_cast<double>(keyframes.size()), "", pose->second});
  }
  if (!keyframes.empty()) WriteRedwoodLog(File(RunLayout::Undistorted("trajectory.log")), keyframes);
}

void FolderRunSink::WriteCamera(const CameraFile& camera) {
  SaveCameraFile(File(RunLayout::kCamera), camera);
  undistort_x_ = undistort_y_ = cv::Mat();
  if (camera.camera.HasDistortion()) camera.camera.UndistortionMaps(&undistort_x_, &undistort_y_);
  CameraFile pinhole = camera;
  pinhole.camera.distortion = {};
  SaveCameraFile(File(RunLayout::Undistorted("camera.json")), pinhole);
  const Camera& c = pinhole.camera;
  const nlohmann::ordered_json open3d = {
      {"width", c.width},
      {"height", c.height},
      {"intrinsic_matrix", {c.fx, 0.0, 0.0, 0.0, c.fy, 0.0, c.cx, c.cy, 1.0}}};  // column-major
  WriteTextFileAtomically(File(RunLayout::Undistorted("camera_intrinsic.json")),
                          open3d.dump(2) + "\n");
}

void FolderRunSink::WriteReport(const RunReport& report) {
  WriteTextFileAtomically(File(RunLayout::kReport), JsonText(nlohmann::ordered_json(report)) + "\n");
}

void FolderRunSink::WriteMap(const std::vector<Surfel>& surfels) {
  WriteSurfelPly(File(RunLayout::kMap), surfels);
}

void InMemoryRunSink::WriteMap(const std::vector<Surfel>& surfels) {
  std::lock_guard<std::mutex> lock(mutex_);
  map = surfels;
  map_written = true;
}

void InMemoryRunSink::WriteKeyframe(const std::string& name, const RgbdFrame& frame,
                                    const CarriedFillResult& fill) {
  std::lock_guard<std::mutex> lock(mutex_);
  keyframes[name] = {frame, fill, cv::Mat(), cv::Mat()};
}

cv::Mat InMemoryRunSink::KeyframeColor(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto found = keyframes.find(name);
  if (found == keyframes.end() || found->second.frame.color.type() != CV_8UC3) return {};
  return found->second.frame.color;
}

int InMemoryRunSink::CompleteKeyframe(const std::string& name, const MapCompletion& offer) {
  Keyframe* found = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    found = &keyframes.at(name);  // (a map's elements stay where they are)
  }
  Keyframe& k = *found;  // one thread completes one keyframe
  k.glass_mask = offer.glass.clone();
  k.fill.filled_depth = k.fill.filled_depth.clone();  // (it may share pixels with the fill's)
  cv::Mat* confidence = nullptr;
  if (k.fill.confidence.type() == CV_32FC1 && k.fill.confidence.size() == offer.depth.size()) {
    k.fill.confidence = k.fill.confidence.clone();
    confidence = &k.fill.confidence;
  }
  return CompleteFromModel(k.frame.hole_mask, offer, &k.fill.filled_depth, confidence,
                           &k.model_fill);
}

void InMemoryRunSink::WriteTrajectory(const Trajectory& t) {
  std::lock_guard<std::mutex> lock(mutex_);
  trajectory = t;
}

void InMemoryRunSink::WriteCamera(const CameraFile& c) {
  std::lock_guard<std::mutex> lock(mutex_);
  camera = c;
}

void InMemoryRunSink::WriteReport(const RunReport& r) {
  std::lock_guard<std::mutex> lock(mutex_);
  report = r;
}

}  // namespace gf
