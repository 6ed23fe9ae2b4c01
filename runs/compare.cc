#include "runs/compare.h"

#include <cstdio>
#include <filesystem>
#include <utility>

#include "acquisition/camera.h"
#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "acquisition/image_io.h"
#include "acquisition/json_text.h"
#include "acquisition/run_folder.h"
#include "acquisition/run_layout.h"
#include "acquisition/trajectory.h"
#include "eval/map_truth.h"
#include "pipeline/run_reader.h"
#include "pipeline/run_sink.h"
#include "report/compare_report.h"
#include "report/report_html.h"
#include "surfels/render.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

using json = nlohmann::ordered_json;

// Both maps rendered from the same two viewpoints: the middle frame's, and looking down on the map
// from above and behind that camera. Written as DIR/<map>_<view>.png.
void WriteRenderings(RunFolder* out, const Camera& camera, const Trajectory& trajectory) {
  const RunLayout folder(out->dir());
  const std::vector<Surfel> with = RunReader(folder.Map(true)).Map();
  const std::vector<Surfel> without = RunReader(folder.Map(false)).Map();
  if (trajectory.empty() || with.empty()) return;
  const SE3 middle = trajectory[trajectory.size() / 2].world_from_camera;
  const Eigen::Matrix3d r = middle.RotationMatrix();
  const SE3 above = ViewOfMap(with, camera, r * Eigen::Vector3d(0, 0.8, 0.6), -r.col(1));
  for (const auto& [pose, view] : {std::pair{middle, "camera"}, std::pair{above, "above"}})
    for (const auto& [map, with_fill] : {std::pair{&with, true}, std::pair{&without, false}})
      WriteImage(out->File(RunLayout::Rendering(with_fill, view)),
                 RenderSurfels(*map, camera, pose, {}).color);
}

}  // namespace

std::string CompareSummary::BriefReport() const {
  char buffer[240];
  std::snprintf(buffer, sizeof(buffer), "%d frames, %ld surfels with the fill, %ld without",
                run.frames, run.surfels, run.surfels_without_fill);
  return buffer;
}

CompareSummary RunCompare(const ReconstructOptions& given) {
  ReconstructOptions options = given;
  options.pipeline.fill = options.pipeline.fusion = true;
  RunFolder::Options folder_options;
  std::unique_ptr<FrameSource> source = OpenRunInput(options, &folder_options);
  // One marker and lock for the whole comparison: with_fill/ and without_fill/ are recorded in it.
  RunFolder folder(options.out_dir, folder_options);
  FolderRunSink with(&folder, RunLayout::kWithFill);
  FolderRunSink without(&folder, RunLayout::kWithoutFill);
  CompareSummary summary;
  summary.run = RunPipeline(options, source.get(), &with, &without, "compare");
  json& c = summary.compare;
  c["input"] = options.input;
  c["frames"] = summary.run.frames;
  for (const char* v : {"with_fill", "without_fill"}) {
    const RunReport& run =
        std::string(v) == "with_fill" ? summary.run.report : summary.run.report_without_fill;
    c[v]["surfels"] = run.surfels ? json(*run.surfels) : json();
    const json truth = EvaluateMapAgainstTruth(options.input, RunLayout(options.out_dir).Path(v));
    if (truth.is_null()) continue;
    c[v]["completeness"] = truth["completeness"];
    c[v]["accuracy"] = truth["accuracy"];
    c["ate_m"] = truth["ate_m"];
  }
  WriteTextFileAtomically(folder.File(RunLayout::kCompare), JsonText(c) + "\n");
  WriteRenderings(&folder, source->camera(),
                  RunReader(RunLayout(options.out_dir).Map(true)).Poses());
  HtmlReport r("GlassFusion: the model with and without the stereo fill");
  AddComparisonSections(&r, options.out_dir, "",
                        [&](const std::string& name) { return folder.File(name); });
  WriteTextFileAtomically(folder.File(RunLayout::kPage), r.Html());
  return summary;
}

}  // namespace gf
