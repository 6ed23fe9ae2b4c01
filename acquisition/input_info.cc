#include "acquisition/input_info.h"

#include "acquisition/depth.h"
#include "acquisition/stats.h"

namespace gf {
namespace {

// The camera's size and intrinsics.
void AddCamera(const Camera& c, nlohmann::ordered_json* j) {
  (*j)["width"] = c.width;
  (*j)["height"] = c.height;
  (*j)["intrinsics"] = {{"fx", c.fx},
                        {"fy", c.fy},
                        {"cx", c.cx},
                        {"cy", c.cy},
                        {"distortion", c.DistortionCoefficients()}};
}

// Where the reader registered depth to colour: the depth camera and where it sits.
void AddDepthCamera(const CameraFile& cf, nlohmann::ordered_json* j) {
  if (!cf.depth_camera) return;
  const Camera& d = *cf.depth_camera;
  const Eigen::Vector3d t = cf.color_from_depth.translation();
  (*j)["depth_camera"] = {{"width", d.width}, {"height", d.height}, {"fx", d.fx},
                          {"fy", d.fy},       {"cx", d.cx},         {"cy", d.cy},
                          {"distortion", d.DistortionCoefficients()}};
  (*j)["color_from_depth"] = {
      {"translation_m", {t.x(), t.y(), t.z()}},
      {"rotation_deg",
       cf.color_from_depth.rotation().angularDistance(Eigen::Quaterniond::Identity()) * 180 /
           M_PI}};
}

}  // namespace

nlohmann::ordered_json InputInfo(const std::string& input, FrameSourceOptions options,
                                 const std::function<void(int, int)>& progress) {
  options.load_color =
      false;  // holes are a property of depth; colour decoding would double the time
  std::unique_ptr<FrameSource> source = OpenFrameSource(input, options);
  const CameraFile& cf = source->camera_file();
  const int total = source->FrameCount().value_or(0);

  HoleStats holes;
  RgbdFrame frame;
  int frames = 0, without_depth = 0;
  double first_time = 0, last_time = 0;
  std::vector<double> medians;  // per frame with returns: the median return depth, metres
  while (source->Next(&frame)) {
    holes += frame.sensor_holes;
    if (frame.median_return_m > 0)
      medians.push_back(frame.median_return_m);
    else
      ++without_depth;
    if (frames == 0) first_time = frame.timestamp;
    last_time = frame.timestamp;
    ++frames;
    if (progress) progress(frames, total);
  }

  nlohmann::ordered_json j;
  j["input"] = input;
  j["source"] = source->Kind();
  j["frames"] = frames;
  if (auto* folder = dynamic_cast<FolderFrameSource*>(source.get())) {
    j["depth_frames"] = folder->listed_depth;
    j["color_frames"] = folder->listed_color;
    j["unmatched_depth"] = folder->unmatched_depth;
    j["unmatched_color"] = folder->unmatched_color;
  }
  if (source->Kind() == "tum" || source->Kind() == "realsense_bag" ||
      source->Kind() == "azure_kinect_mkv")
    j["duration_s"] = last_time - first_time;
  AddCamera(cf.camera, &j);
  j["depth_convention"] = source->depth_convention().Name();
  j["depth_scale"] = cf.depth_scale;
  j["depth_registered_to_color"] = cf.depth_registered_to_color;
  AddDepthCamera(cf, &j);
  const double pixels = static_cast<double>(holes.pixels);
  j["hole_fraction"] = holes.Fraction();
  j["holes"] = {{"no_return", pixels ? holes.no_return / pixels : 0.0},
                {"out_of_range", pixels ? holes.out_of_range / pixels : 0.0},
                {"shadow", pixels ? holes.shadow / pixels : 0.0}};
  // What would make a reconstruction of this input fail or go wrong, said plainly.
  nlohmann::ordered_json warnings = nlohmann::ordered_json::array();
  if (auto* folder = dynamic_cast<FolderFrameSource*>(source.get())) {
    const int missing = folder->MissingColorFiles();
    if (missing > 0)
      warnings.push_back(std::to_string(missing) + " of " + std::to_string(frames) +
                         " frames list a colour image that is not there");
  }
  if (frames > 0 && without_depth == frames)
    warnings.push_back("no frame has any depth: every pixel is a hole");
  else if (without_depth > 0)
    warnings.push_back(std::to_string(without_depth) + " of " + std::to_string(frames) +
                       " frames have no depth at all");
  const double median_depth = Median(medians, 0.0);
  j["median_depth_m"] =
      medians.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(median_depth);
  const std::string scale = DepthScaleProblem(median_depth, source->depth_convention());
  if (!scale.empty()) warnings.push_back(scale);
  j["warnings"] = warnings;
  return j;
}

}  // namespace gf
