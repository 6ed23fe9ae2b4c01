// COLMAP interop: the text sparse model (cameras.txt, images.txt, points3D.txt) and the binary
// depth maps that `colmap patch_match_stereo` writes (stereo/depth_maps/<image>.{geometric,
// photometric}.bin).
//
// Conventions (COLMAP 3.8 documentation, "Output Format"): images.txt stores camera_from_world as
// QW QX QY QZ TX TY TZ, one line per image followed by its 2D points line (empty here); camera
// models used: PINHOLE, SIMPLE_PINHOLE, OPENCV, FULL_OPENCV (our 5-coefficient distortion is
// FULL_OPENCV with k4 = k5 = k6 = 0). A depth map is the text header "width&height&channels&"
// followed by little-endian float32 values, channel planes of row-major rows.
//
// Readers throw InputError naming the file on missing files, malformed lines, unknown camera
// models and truncated depth maps. Writers are atomic (temporary name, then rename).
#pragma once

#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/se3.h"

namespace gf {

struct ColmapImage {
  int id = 0;  // COLMAP image_id (1-based)
  int camera_id = 1;
  std::string name;  // file name under the image folder
  SE3 world_from_camera;
};

// Writes cameras.txt (one camera, id 1), images.txt and an empty points3D.txt into sparse_dir.
void WriteColmapTextModel(const std::string& sparse_dir, const Camera& camera,
                          const std::vector<ColmapImage>& images);

// Reads cameras.txt of a text model: camera_id -> Camera.
std::map<int, Camera> ReadColmapCameras(const std::string& path);
// Reads images.txt of a text model.
std::vector<ColmapImage> ReadColmapImages(const std::string& path);

// CV_32F depth (metres in COLMAP's units; 0 = none) of a depth map .bin (first channel).
cv::Mat ReadColmapDepthMap(const std::string& path);
void WriteColmapDepthMap(const std::string& path, const cv::Mat& depth);

}  // namespace gf
