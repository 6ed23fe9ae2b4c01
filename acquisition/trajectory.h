// Camera trajectories: the TUM text format and the Redwood / Open3D .log format.
//
// TUM (https://vision.in.tum.de/data/datasets/rgbd-dataset/file_formats): one pose per line,
//   timestamp tx ty tz qx qy qz qw
// where (t, q) is world_from_camera; lines starting with '#' are comments.
// Redwood .log: per frame a header line "id0 id1 frame_count" and four lines of the 4x4
// world_from_camera matrix. The frame index (id0) becomes the pose's timestamp.
//
// Readers throw InputError("<file>: line N: ...") on malformed content and on an empty trajectory;
// writers are atomic (temporary name, then rename).
#pragma once

#include <string>
#include <vector>

#include "acquisition/se3.h"

namespace gf {

struct StampedPose {
  double timestamp = 0;        // seconds (TUM) or frame index (Redwood)
  std::string timestamp_text;  // exactly as read, or empty; written verbatim when present
  SE3 world_from_camera;
};
using Trajectory = std::vector<StampedPose>;

Trajectory ReadTumTrajectory(const std::string& path);
void WriteTumTrajectory(const std::string& path, const Trajectory& trajectory);

Trajectory ReadRedwoodLog(const std::string& path);
// Frame i is written with the header "i i i+1", as Open3D does; timestamps are rounded to indices.
void WriteRedwoodLog(const std::string& path, const Trajectory& trajectory);

// Either format, chosen by the extension (.log = Redwood, anything else = TUM).
Trajectory ReadTrajectory(const std::string& path);

// The ground truth beside an input folder: INPUT/groundtruth.txt (TUM) or INPUT/groundtruth.log
// (Redwood); "" when it has none.
std::string GroundTruthBeside(const std::string& input);

}  // namespace gf
