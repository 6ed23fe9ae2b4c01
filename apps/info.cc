#include "apps/info.h"

#include "acquisition/depth.h"

namespace gf {

nlohmann::ordered_json InputInfo(const std::string& input, FrameSourceOptions options,
                                 const std::function<void(int, int)>& progress) {
  options.load_color =
      false;  // holes are a property of depth; colour decoding would double the time
  std::unique_ptr<FrameSource> source = OpenFrameSource(input, options);
  const CameraFile& cf = source->camera_file();
  const Camera& c = cf.camera;
  const int total = source->FrameCount().value_or(0);

  HoleStats holes;
  RgbdFrame frame;
  int frames = 0;
  double first_time = 0, last_time = 0;
  while (source->Next(&frame)) {
    holes += frame.sensor_holes;
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
  if (source->Kind() == "tum") j["duration_s"] = last_time - first_time;
  j["width"] = c.width;
  j["height"] = c.height;
  j["intrinsics"] = {{"fx", c.fx},
                     {"fy", c.fy},
                     {"cx", c.cx},
                     {"cy", c.cy},
                     {"distortion", std::vector<double>(c.distortion.begin(), c.distortion.end())}};
  j["depth_convention"] = source->depth_convention().Name();
  j["depth_scale"] = cf.depth_scale;
  j["depth_registered_to_color"] = cf.depth_registered_to_color;
  const double pixels = static_cast<double>(holes.pixels);
  j["hole_fraction"] = holes.Fraction();
  j["holes"] = {{"no_return", pixels ? holes.no_return / pixels : 0.0},
                {"out_of_range", pixels ? holes.out_of_range / pixels : 0.0},
                {"shadow", pixels ? holes.shadow / pixels : 0.0}};
  return j;
}

}  // namespace gf
