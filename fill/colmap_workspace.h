// `glassfusion colmap-export RUN_DIR --out WS` and `colmap-import WS --into RUN_DIR`.
//
// Export writes a COLMAP workspace from a reconstruct run: WS/images/<NNNNNN>_<ts>.png (the
// keyframes' colour images; names sort in keyframe order, so `colmap feature_extractor` gives
// them the image ids of the model) and WS/sparse/0/{cameras,images,points3D}.txt, COLMAP's usual
// layout, with the tracked keyframe poses (one FULL_OPENCV camera carrying the input's lens
// distortion, as the images are the input's own; no points: `colmap point_triangulator` makes
// them). The workspace folder appears only when complete.
//
// Import reads back what COLMAP made:
//  - refined poses: a text model (default WS/refined, e.g. after point_triangulator +
//    bundle_adjuster + model_converter --output_type TXT) -> RUN_DIR/trajectory_colmap.txt
//    (TUM format, keyframe depth timestamps);
//  - depth maps of patch_match_stereo (WS/stereo/depth_maps or WS/dense/stereo/depth_maps,
//    <image>.geometric.bin preferred over .photometric.bin, on the pixel grid of the dense
//    workspace's sparse/cameras.txt when there is one): an additional fill source for the holes
//    the stereo fill left empty in keyframes/<ts>.depth_filled.png. A map is used only where it
//    agrees with the sensor on measured pixels (median relative error <= max_sensor_error);
//    measured pixels are never changed.
// A summary goes to RUN_DIR/colmap_import.json. RUN_DIR must be a run folder (its marker
// .glassfusion-run, acquisition/run_folder.h): import takes its lock and lists what it writes
// there, so a later `reconstruct --force` removes it too.
#pragma once

#include <string>

namespace gf {

struct ColmapExportSummary {
  int images = 0;
  std::string BriefReport() const;
};
ColmapExportSummary RunColmapExport(const std::string& run_dir, const std::string& workspace);

struct ColmapImportOptions {
  std::string model_dir;           // empty: WS/refined when it has images.txt
  double max_sensor_error = 0.05;  // depth map vs sensor, median relative error
  int min_sensor_samples = 200;    // fewer pixels to compare: the map is not used
  double min_depth_m = 0.3, max_depth_m = 8.0;
  bool Check(std::string* message = nullptr) const;
};

struct ColmapImportSummary {
  int poses = 0;            // keyframe poses written to trajectory_colmap.txt
  int depth_maps = 0;       // depth maps found
  int depth_maps_used = 0;  // ... that agreed with the sensor
  long filled_pixels = 0;   // holes filled from them
  std::string BriefReport() const;
};
ColmapImportSummary RunColmapImport(const std::string& workspace, const std::string& run_dir,
                                    const ColmapImportOptions& options);

}  // namespace gf
