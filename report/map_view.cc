#include "pipeline/run_reader.h"
#include "report/map_view.h"

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory.h"
#include "pipeline/run_sink.h"
#include "report/run_report.h"
#include "surfels/ply.h"

namespace gf {

// The bundled viewer (viewer/, built into the executable by CMake; empty when it was not built).
extern const char* const kViewerBundle;

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

// Base64 of bytes [begin, end).
std::string Base64(const char* begin, const char* end) {
  const std::string bytes(begin, end);
  static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = static_cast<uint8_t>(bytes[i]) << 16 |
                       static_cast<uint8_t>(bytes[i + 1]) << 8 | static_cast<uint8_t>(bytes[i + 2]);
    for (int shift : {18, 12, 6, 0}) out += kDigits[(v >> shift) & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const uint32_t v = static_cast<uint8_t>(bytes[i]) << 16 |
                       (two ? static_cast<uint8_t>(bytes[i + 1]) << 8 : 0);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += two ? kDigits[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The map's surfels for the page: all of them, or every k-th (evenly spread, the same each run)
// when there are more than kMaxViewSurfels.
std::vector<Surfel> ForThePage(const std::vector<Surfel>& surfels) {
  if (surfels.size() <= kMaxViewSurfels) return surfels;
  std::vector<Surfel> kept;
  kept.reserve(kMaxViewSurfels);
  for (size_t i = 0; i < surfels.size(); ++i)
    if ((i + 1) * kMaxViewSurfels / surfels.size() > i * kMaxViewSurfels / surfels.size())
      kept.push_back(surfels[i]);
  return kept;
}

// Base64 in chunks of 256 KiB of text (a browser reads a script of many short string literals
// about three times faster than one holding a single huge literal: 1.6 s against 4.6 s for 48 MB
// in headless Chromium); each chunk holds whole 3-byte groups and decodes alone.
json Base64Chunks(const std::string& bytes) {
  constexpr size_t kChunkBytes = 3 * 65536;
  json chunks = json::array();
  for (size_t i = 0; i < bytes.size(); i += kChunkBytes)
    chunks.push_back(Base64(bytes.data() + i, bytes.data() + std::min(bytes.size(), i + kChunkBytes)));
  return chunks;
}

json MapJson(const ViewedMap& map) {
  const RunReader run(map.run_dir);
  const std::vector<Surfel> surfels =
      run.Has(RunLayout::kMap) ? run.Map() : std::vector<Surfel>();
  const std::vector<Surfel> shown = ForThePage(surfels);
  return {{"name", map.name},
          {"surfels_total", surfels.size()},
          {"surfels_shown", shown.size()},
          {"ply_base64", Base64Chunks(SurfelPlyBytes(shown, /*normals=*/false))}};
}

// The camera path, and each keyframe's pose and fill overlay (paths relative to the report).
void AddPath(const ViewedMap& map, json* view) {
  const RunReader run(map.run_dir);
  const Trajectory trajectory = run.Has(RunLayout::kTrajectory) ? run.Poses() : Trajectory();
  json centres = json::array();
  for (const StampedPose& p : trajectory) {
    const Eigen::Vector3d c = p.world_from_camera.translation();
    centres.push_back({c.x(), c.y(), c.z()});
  }
  (*view)["trajectory"] = centres;
  json keyframes = json::array();
  for (const std::string& file : KeyframeFiles(map.run_dir)) {
    const std::string ts = StampOfIndexedName(file);
    if (ts.empty()) continue;
    const double t = std::stod(ts);
    const StampedPose* nearest = nullptr;
    for (const StampedPose& p : trajectory)
      if (!nearest || std::abs(p.timestamp - t) < std::abs(nearest->timestamp - t)) nearest = &p;
    if (!nearest || std::abs(nearest->timestamp - t) > 1e-3) continue;
    const Eigen::Matrix4d m = nearest->world_from_camera.Matrix();
    json pose = json::array();
    for (int row = 0; row < 4; ++row)
      for (int col = 0; col < 4; ++col) pose.push_back(m(row, col));
    const std::string overlay = RunLayout::Keyframe(ts, KeyframeImage::kFillOverlay);
    const bool has_overlay = run.Has(overlay);
    keyframes.push_back({{"label", FrameLabel(file)},
                         {"world_from_camera", pose},
                         {"overlay", has_overlay ? map.prefix + overlay : ""}});
  }
  (*view)["keyframes"] = keyframes;
  const Camera c = run.Has(RunLayout::kCamera) ? run.ImageCamera() : Camera();
  (*view)["camera"] = {{"width", c.width}, {"height", c.height}, {"fx", c.fx},
                       {"fy", c.fy},       {"cx", c.cx},         {"cy", c.cy}};
}

}  // namespace

bool MapViewAvailable() { return kViewerBundle[0] != '\0'; }

void AddMapView(HtmlReport* r, const ReportFile& file, const std::vector<ViewedMap>& maps) {
  if (!MapViewAvailable()) {
    r->Paragraph("(No 3D view: this build of GlassFusion has no viewer; node and npm were "
                 "missing when it was built.)");
    return;
  }
  if (maps.empty()) return;
  json view;
  view["maps"] = json::array();
  for (const ViewedMap& map : maps) view["maps"].push_back(MapJson(map));
  AddPath(maps.front(), &view);
  WriteTextFileAtomically(file("gf_viewer.js"), kViewerBundle);
  WriteTextFileAtomically(file("view_data.js"), "window.GF_VIEW = " + view.dump() + ";\n");
  r->Paragraph(
      "The maps in 3D (drag to turn, right-drag to pan, wheel to zoom; both turn together). "
      "Colour by the surfels' colour, their source (grey sensor, green stereo fill, blue clear "
      "glass) or confidence; a box per source shows or hides it; click a keyframe's frustum for "
      "its fill overlay.");
  r->RawHtml(
      "<div id=\"gf-view\"></div>\n<script src=\"view_data.js\"></script>\n"
      "<script src=\"gf_viewer.js\"></script>\n"
      "<script>GFViewer.mount(document.getElementById('gf-view'), window.GF_VIEW);</script>\n");
}

}  // namespace gf
