#include "pipeline/run_reader.h"

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "surfels/ply.h"

namespace gf {

bool RunReader::Has(const std::string& relative) const {
  return IsRegularFile(layout_.Path(relative));
}

RunReport RunReader::Report() const {
  const std::string path = layout_.Path(RunLayout::kReport);
  try {
    return nlohmann::ordered_json::parse(ReadTextFile(path)).get<RunReport>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not a run's report: ") + e.what());
  }
}

Trajectory RunReader::Poses() const {
  return ReadTumTrajectory(layout_.Path(RunLayout::kTrajectory));
}

Camera RunReader::ImageCamera() const {
  return LoadCameraFile(layout_.Path(RunLayout::kCamera)).camera;
}

std::vector<Surfel> RunReader::Map() const {
  return ReadSurfelPly(layout_.Path(RunLayout::kMap));
}

}  // namespace gf
