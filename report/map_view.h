// The reports' interactive 3D view: one or two surfel maps side by side in the browser, with one
// shared camera, the camera path, keyframe frusta and their fill overlays (viewer/README.md).
//
// The page needs no server and no network: the view is a plain script (three.js and the viewer,
// bundled by esbuild when GlassFusion is built, embedded in the executable) and a data script
// holding the maps (binary PLY, base64), both written beside report.html:
//   gf_viewer.js    the viewer
//   view_data.js    window.GF_VIEW = {maps, trajectory, keyframes, camera}; each map a binary
//                   PLY as map.ply without the normals, base64 in chunks
// A map larger than kMaxViewSurfels is subsampled for the page (every k-th surfel, the same on
// every run) and the page says so; map.ply keeps every surfel.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "report/report_html.h"

namespace gf {

inline constexpr size_t kMaxViewSurfels = 500'000;  // per map, surfels on the page

// A run folder whose map.ply the view shows, under `name` ("with fill").
struct ViewedMap {
  std::string name;
  std::string run_dir;
  std::string prefix;  // the run folder as seen from the report's folder: "" or "with_fill/"
};

// Whether this build holds the viewer (node and npm were there when it was built).
bool MapViewAvailable();

// The path to write a file of the report's folder to, by its name (RunFolder::File: it refuses a
// path that holds a file of the user's).
using ReportFile = std::function<std::string(const std::string& name)>;

// Writes gf_viewer.js and view_data.js beside the report and adds the view to it: the maps'
// map.ply files, the trajectory and keyframes of the first map's run. Says in the report why there
// is no view when the build has none. Throws InputError when a file cannot be written.
void AddMapView(HtmlReport* r, const ReportFile& file, const std::vector<ViewedMap>& maps);

}  // namespace gf
