#include "acquisition/frame_source.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "acquisition/azure_kinect_mkv.h"
#include "acquisition/bounds.h"
#include "acquisition/depth_registration.h"
#include "acquisition/devices.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/realsense_bag.h"
#include "acquisition/tum_index.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

// Depth and colour index lines paired one-to-one by time (AssociateTimestamps).
std::vector<FolderFrameEntry> PairByTime(const std::vector<IndexLine>& depth,
                                         const std::vector<IndexLine>& color, double max_dt) {
  std::vector<double> td, tc;
  for (const auto& d : depth) td.push_back(d.timestamp);
  for (const auto& c : color) tc.push_back(c.timestamp);
  std::vector<FolderFrameEntry> entries;
  for (const auto& [i, j] : AssociateTimestamps(td, tc, max_dt)) {
    FolderFrameEntry e;
    e.timestamp = depth[i].timestamp;
    e.timestamp_text = depth[i].timestamp_text;
    e.color_timestamp = color[j].timestamp;
    e.depth_path = depth[i].path;
    e.color_path = color[j].path;
    entries.push_back(e);
  }
  return entries;
}

// Depth and colour files paired by sorted position; the frame index stands in for time.
std::vector<FolderFrameEntry> PairByIndex(const std::vector<std::string>& depths,
                                          const std::vector<std::string>& colors) {
  std::vector<FolderFrameEntry> entries;
  for (size_t i = 0; i < depths.size(); ++i) {
    FolderFrameEntry e;
    e.timestamp = e.color_timestamp = static_cast<double>(i);
    e.timestamp_text = std::to_string(i);
    e.depth_path = depths[i];
    e.color_path = colors[i];
    entries.push_back(e);
  }
  return entries;
}

// --camera FILE when given, else <folder>/camera.json.
std::string CameraPathFor(const std::string& folder, const FrameSourceOptions& options) {
  return options.camera_file.empty() ? (fs::path(folder) / "camera.json").string()
                                     : options.camera_file;
}

CameraFile LoadFolderCamera(const std::string& folder, const FrameSourceOptions& options) {
  const std::string path = CameraPathFor(folder, options);
  if (!IsRegularFile(path))
    throw InputError(path, "camera intrinsics not found (add camera.json or pass --camera FILE)");
  return LoadCameraFile(path);
}

std::vector<std::string> ImagesIn(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm")
      files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string FirstExistingDir(const std::string& folder, std::initializer_list<const char*> names) {
  for (const char* n : names) {
    const std::string p = (fs::path(folder) / n).string();
    if (IsDirectory(p)) return p;
  }
  return {};
}

}  // namespace

bool FrameSourceOptions::Check(std::string* message) const {
  // Colour and depth stamps further apart than a second are not one frame.
  FieldCheck c(message);
  c.Part("depth", depth)
      .Part("shadows", shadows)
      .Above("max_association_dt_s", max_association_dt_s, 0, 1, "is more than a second");
  return c.ok();
}

void ProcessRawDepth(const cv::Mat& raw, const std::string& where, const CameraFile& camera,
                     const DepthConvention& convention, const FrameSourceOptions& options,
                     RgbdFrame* f) {
  const bool registered = camera.depth_registered_to_color;
  const Camera& depth_cam = registered ? camera.camera : *camera.depth_camera;
  if (raw.cols != depth_cam.width || raw.rows != depth_cam.height) {
    std::ostringstream s;
    s << "depth image is " << raw.cols << "x" << raw.rows << " but the "
      << (registered ? "camera" : "depth camera") << " is " << depth_cam.width << "x"
      << depth_cam.height;
    throw InputError(where, s.str());
  }
  const std::string problem = convention.ValidateRaw(raw);
  if (!problem.empty()) throw InputError(where, problem);
  ConvertDepth(raw, convention, options.depth, &f->depth, &f->hole_mask);
  f->median_return_m = MedianReturnDepth(raw, convention);
  ClassifyShadows(f->depth, depth_cam.fx, options.shadows, &f->hole_mask);
  f->sensor_holes = CountHoles(f->hole_mask);
  if (!registered) {
    cv::Mat depth, holes;
    RegisterDepthToColor(f->depth, f->hole_mask, depth_cam, camera.camera, camera.color_from_depth,
                         &depth, &holes);
    f->depth = depth;
    f->hole_mask = holes;
  }
}

namespace {

// The size of an image from its header, or from decoding it where the header is of no format
// ReadImageSize knows; nullopt when the file is not there (Next() reports that).
std::optional<cv::Size> ImageSize(const std::string& path, bool depth) {
  if (!IsRegularFile(path)) return std::nullopt;
  if (const std::optional<cv::Size> size = ReadImageSize(path)) return size;
  return (depth ? ReadDepthImage(path) : ReadColorImage(path)).size();
}

void CheckImageSize(const std::string& path, const char* what, const cv::Size& size,
                    const char* camera_name, const Camera& camera) {
  std::ostringstream s;
  if (size.width < kMinImageWidthPx || size.height < kMinImageHeightPx) {
    s << what << " image is " << size.width << "x" << size.height
      << ", smaller than the least GlassFusion works on (" << kMinImageWidthPx << "x"
      << kMinImageHeightPx << ")";
    throw InputError(path, s.str());
  }
  if (size.width != camera.width || size.height != camera.height) {
    s << what << " image is " << size.width << "x" << size.height << " but the " << camera_name
      << " is " << camera.width << "x" << camera.height;
    throw InputError(path, s.str());
  }
}

}  // namespace

void FolderFrameSource::CheckFirstFrame(const FolderFrameEntry& first, const CameraFile& camera) {
  const bool registered = camera.depth_registered_to_color;
  if (const auto size = ImageSize(first.depth_path, true))
    CheckImageSize(first.depth_path, "depth", *size, registered ? "camera" : "depth camera",
                   registered ? camera.camera : *camera.depth_camera);
  if (first.color_path.empty()) return;
  if (const auto size = ImageSize(first.color_path, false))
    CheckImageSize(first.color_path, "colour", *size, "camera", camera.camera);
}

int FolderFrameSource::MissingColorFiles() const {
  int missing = 0;
  for (const FolderFrameEntry& e : entries_)
    missing += !e.color_path.empty() && !IsRegularFile(e.color_path);
  return missing;
}

FolderFrameSource::FolderFrameSource(std::string kind, std::string input, CameraFile camera,
                                     DepthConvention convention,
                                     std::vector<FolderFrameEntry> entries,
                                     FrameSourceOptions options)
    : kind_(std::move(kind)),
      input_(std::move(input)),
      camera_(camera),
      convention_(convention),
      entries_(std::move(entries)),
      options_(std::move(options)) {
  std::string problem;
  GF_CHECK(options_.Check(&problem), problem);
  if (!entries_.empty()) CheckFirstFrame(entries_.front(), camera_);
}

bool FolderFrameSource::Next(RgbdFrame* frame) {
  if (next_ >= entries_.size()) return false;
  const FolderFrameEntry& e = entries_[next_];
  RgbdFrame f;
  f.index = static_cast<int>(next_);
  f.timestamp = e.timestamp;
  f.timestamp_text = e.timestamp_text;
  f.color_timestamp = e.color_timestamp;
  f.color_path = e.color_path;
  f.depth_path = e.depth_path;
  const Camera& cam = camera_.camera;
  ProcessRawDepth(ReadDepthImage(e.depth_path), e.depth_path, camera_, convention_, options_, &f);
  if (options_.load_color) {
    f.color = ReadColorImage(e.color_path);
    if (f.color.cols != cam.width || f.color.rows != cam.height) {
      std::ostringstream s;
      s << "colour image is " << f.color.cols << "x" << f.color.rows << " but the camera is "
        << cam.width << "x" << cam.height << " (depth image " << e.depth_path << ")";
      throw InputError(e.color_path, s.str());
    }
  }
  *frame = std::move(f);
  ++next_;
  return true;
}

std::unique_ptr<FolderFrameSource> OpenTumFolder(const std::string& folder,
                                                 const FrameSourceOptions& options) {
  for (const char* name : {"rgb.txt", "depth.txt"}) {
    const std::string problem = IndexFileProblem((fs::path(folder) / name).string());
    if (!problem.empty())
      throw InputError((fs::path(folder) / name).string(),
                       problem + " (a TUM folder needs both rgb.txt and depth.txt)");
  }
  const std::vector<IndexLine> depth = ReadTumIndex(folder, "depth.txt");
  const std::vector<IndexLine> color = ReadTumIndex(folder, "rgb.txt");
  const CameraFile camera = LoadFolderCamera(folder, options);
  const std::vector<FolderFrameEntry> entries =
      PairByTime(depth, color, options.max_association_dt_s);
  const size_t pairs = entries.size();
  if (entries.empty())
    throw InputError((fs::path(folder) / "depth.txt").string(),
                     "no depth frame has a colour frame within " +
                         std::to_string(options.max_association_dt_s * 1000) + " ms");
  auto source = std::make_unique<FolderFrameSource>(
      "tum", folder, camera, DepthConvention::FromDepthScale(camera.depth_scale),
      std::move(entries), options);
  source->listed_depth = static_cast<int>(depth.size());
  source->listed_color = static_cast<int>(color.size());
  source->unmatched_depth = static_cast<int>(depth.size() - pairs);
  source->unmatched_color = static_cast<int>(color.size() - pairs);
  if (source->unmatched_depth || source->unmatched_color)
    spdlog::info("{}: dropped {} depth and {} colour frames without a partner within {} ms", folder,
                 source->unmatched_depth, source->unmatched_color,
                 options.max_association_dt_s * 1000);
  return source;
}

std::unique_ptr<FolderFrameSource> OpenRedwoodFolder(const std::string& folder,
                                                     const FrameSourceOptions& options) {
  const std::string color_dir = FirstExistingDir(folder, {"image", "color", "rgb"});
  if (color_dir.empty()) throw InputError(folder, "no image/, color/ or rgb/ folder");
  std::string depth_dir;
  if (!options.depth_folder.empty()) {
    depth_dir = (fs::path(folder) / options.depth_folder).string();
    if (!IsDirectory(depth_dir)) throw InputError(depth_dir, "depth folder not found");
  } else {
    depth_dir = FirstExistingDir(folder, {"depth", "depth_noisy"});
    if (depth_dir.empty()) throw InputError(folder, "no depth/ folder");
  }
  const CameraFile camera = LoadFolderCamera(folder, options);
  const std::vector<std::string> colors = ImagesIn(color_dir);
  const std::vector<std::string> depths = ImagesIn(depth_dir);
  if (depths.empty()) throw InputError(depth_dir, "holds no depth images");
  if (colors.size() != depths.size())
    throw InputError(folder, std::to_string(colors.size()) + " colour images in " +
                                 fs::path(color_dir).filename().string() + "/ but " +
                                 std::to_string(depths.size()) + " depth images in " +
                                 fs::path(depth_dir).filename().string() + "/");
  std::vector<FolderFrameEntry> entries = PairByIndex(depths, colors);
  auto source = std::make_unique<FolderFrameSource>(
      "redwood", folder, camera, DepthConvention::FromDepthScale(camera.depth_scale),
      std::move(entries), options);
  source->listed_depth = source->listed_color = static_cast<int>(depths.size());
  return source;
}

CameraFile NominalKinectV1Calibration() {
  CameraFile f;
  f.camera.fx = 529.2;  // colour camera
  f.camera.fy = 525.6;
  f.camera.cx = 328.9;
  f.camera.cy = 267.5;
  Camera ir;
  ir.fx = 594.2;
  ir.fy = 591.0;
  ir.cx = 339.3;
  ir.cy = 242.7;
  f.depth_camera = ir;
  f.depth_registered_to_color = false;
  f.depth_scale = 1000.0;  // not used for disparity
  Eigen::Matrix3d r;
  r << 0.99985, 0.00126, -0.01749, -0.00148, 0.99992, -0.01225, 0.01747, 0.01228, 0.99977;
  f.color_from_depth = SE3::FromMatrix(
      (Eigen::Matrix4d() << r, Eigen::Vector3d(0.01999, -0.00074, -0.01092), 0, 0, 0, 1)
          .finished());
  return f;
}

namespace {

bool StartsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Parses "d-1294352291.235890-2213567.pgm" into its time text and seconds.
bool ParseFakenectName(const std::string& name, std::string* time_text, double* seconds) {
  if (name.size() < 3 || name[1] != '-') return false;
  const size_t dash = name.find('-', 2);
  if (dash == std::string::npos) return false;
  *time_text = name.substr(2, dash - 2);
  try {
    size_t used = 0;
    *seconds = std::stod(*time_text, &used);
    return used == time_text->size() && std::isfinite(*seconds);
  } catch (const std::exception&) {
    return false;
  }
}

CameraFile KinectCamera(const std::string& folder, const FrameSourceOptions& options) {
  const std::string path = CameraPathFor(folder, options);
  if (IsRegularFile(path)) return LoadCameraFile(path);
  if (!options.camera_file.empty()) throw InputError(path, "file not found");
  spdlog::warn("{}: no camera.json; using a nominal Kinect v1 calibration (pass --camera FILE)",
               folder);
  return NominalKinectV1Calibration();
}

}  // namespace

std::unique_ptr<FolderFrameSource> OpenKinectRawFolder(const std::string& folder,
                                                       const FrameSourceOptions& options) {
  const CameraFile camera = KinectCamera(folder, options);
  std::vector<FolderFrameEntry> entries;
  int listed_depth = 0, listed_color = 0;
  const std::string index_path = (fs::path(folder) / "INDEX.txt").string();
  std::string kind = "kinect_raw";
  if (IsRegularFile(index_path)) {
    kind = "fakenect";
    std::istringstream in(ReadTextFile(index_path));
    std::vector<IndexLine> depth, color;
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())))
        line.pop_back();
      if (line.empty()) continue;
      IndexLine entry;
      if (!ParseFakenectName(line, &entry.timestamp_text, &entry.timestamp))
        throw InputError(index_path, "line " + std::to_string(number) + ": \"" + line +
                                         "\" is not a fakenect file name (d-/r-/a-<time>-<n>.*)");
      entry.path = (fs::path(folder) / line).string();
      if (line[0] == 'd') depth.push_back(entry);
      if (line[0] == 'r') color.push_back(entry);
    }
    if (depth.empty()) throw InputError(index_path, "lists no depth frames (d-*.pgm)");
    auto by_time = [](const IndexLine& a, const IndexLine& b) { return a.timestamp < b.timestamp; };
    std::stable_sort(depth.begin(), depth.end(), by_time);
    std::stable_sort(color.begin(), color.end(), by_time);
    entries = PairByTime(depth, color, options.max_association_dt_s);
    listed_depth = static_cast<int>(depth.size());
    listed_color = static_cast<int>(color.size());
    if (entries.empty())
      throw InputError(index_path,
                       "no depth frame has a colour frame within the association window");
  } else {
    std::vector<std::string> depths, colors;
    for (const std::string& path : ImagesIn(folder)) {
      std::string name = fs::path(path).filename().string();
      std::transform(name.begin(), name.end(), name.begin(), ::tolower);
      if (StartsWith(name, "d-") || Contains(name, "depth")) {
        depths.push_back(path);
      } else if (StartsWith(name, "r-") || Contains(name, "color") || Contains(name, "rgb")) {
        colors.push_back(path);
      }
    }
    if (depths.empty()) throw InputError(folder, "no raw depth images (d-*.pgm or *depth*.pgm)");
    if (colors.size() != depths.size())
      throw InputError(folder, std::to_string(depths.size()) + " depth images but " +
                                   std::to_string(colors.size()) + " colour images");
    entries = PairByIndex(depths, colors);
    listed_depth = listed_color = static_cast<int>(depths.size());
  }
  const int pairs = static_cast<int>(entries.size());
  auto source = std::make_unique<FolderFrameSource>(
      kind, folder, camera, DepthConvention::KinectV1Raw11Bit(), std::move(entries), options);
  source->listed_depth = listed_depth;
  source->listed_color = listed_color;
  source->unmatched_depth = listed_depth - pairs;
  source->unmatched_color = listed_color - pairs;
  return source;
}

InMemoryFrameSource::InMemoryFrameSource(CameraFile camera, std::vector<RgbdFrame> frames)
    : camera_(camera), frames_(std::move(frames)) {}

bool InMemoryFrameSource::Next(RgbdFrame* frame) {
  if (next_ >= frames_.size()) return false;
  *frame = frames_[next_++];
  return true;
}

std::string DetectInputKind(const std::string& input) {
  if (IsDirectory(input)) {
    const fs::path p(input);
    // Either index makes it a TUM folder (OpenTumFolder then says which one is unusable): a
    // folder with depth.txt but no usable rgb.txt is not to be read as a Redwood folder, paired by
    // position instead of by time.
    if (PathListed((p / "rgb.txt").string()) || PathListed((p / "depth.txt").string()))
      return "tum";
    if (IsRegularFile((p / "INDEX.txt").string())) return "fakenect";
    const bool has_color = !FirstExistingDir(input, {"image", "color", "rgb"}).empty();
    const bool has_depth = !FirstExistingDir(input, {"depth", "depth_noisy"}).empty();
    if (has_color && has_depth) return "redwood";
    for (const std::string& f : ImagesIn(input))
      if (fs::path(f).extension() == ".pgm") return "kinect_raw";
    return {};
  }
  if (IsRegularFile(input) && fs::path(input).extension() == ".oni") return "oni";
  if (IsRegularFile(input) && fs::path(input).extension() == ".bag") return "realsense_bag";
  if (IsRegularFile(input) && fs::path(input).extension() == ".mkv") return "azure_kinect_mkv";
  return {};
}

std::unique_ptr<FrameSource> OpenFrameSource(const std::string& input,
                                             const FrameSourceOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError(input, "bad frame source options: " + problem);
  // Live devices: "dummy", "openni2[:URI]", "freenect[:INDEX]".
  if (input == "dummy") return OpenOpenNI2Source("Dummy", options);
  if (input == "openni2") return OpenOpenNI2Source("", options);
  if (input.rfind("openni2:", 0) == 0) return OpenOpenNI2Source(input.substr(8), options);
  if (input == "freenect" || input.rfind("freenect:", 0) == 0) {
    int index = 0;
    if (input.size() > 9) {
      try {
        index = std::stoi(input.substr(9));
      } catch (const std::exception&) {
        throw InputError(input, "expected freenect:INDEX with a device number");
      }
    }
    return OpenFreenectSource(index, options);
  }
  if (!fs::exists(input)) throw InputError(input, "no such file or folder");
  const std::string kind = DetectInputKind(input);
  if (kind == "oni") return OpenOpenNI2Source(input, options);
  if (kind == "realsense_bag") return OpenRealSenseBag(input, options);
  if (kind == "azure_kinect_mkv") return OpenAzureKinectMkv(input, options);
  if (kind == "tum") return OpenTumFolder(input, options);
  if (kind == "redwood") return OpenRedwoodFolder(input, options);
  if (kind == "fakenect" || kind == "kinect_raw") return OpenKinectRawFolder(input, options);
  throw InputError(input,
                   "unrecognised input: expected a TUM folder (rgb.txt, depth.txt), a Redwood "
                   "folder (image/ or color/, depth/), a raw Kinect folder (*.pgm, INDEX.txt), an "
                   ".oni file, a RealSense .bag, an Azure Kinect .mkv or a device (dummy, "
                   "openni2[:URI], freenect[:INDEX])");
}

}  // namespace gf
