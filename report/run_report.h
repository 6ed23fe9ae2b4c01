// The sections a report on a run is built from, shared by `reconstruct` (RUN/report.html),
// `compare` (DIR/report.html) and `demo`, so that every report reads the same way:
//   - what the run did: frames, rate, keyframes, lost frames, loops, fill, surfels, ATE when the
//     input has ground truth (its groundtruth.txt);
//   - the trajectory from above, against the ground truth when there is one (the estimate moved
//     onto it by the best rigid alignment, as ATE is measured);
//   - the map's surfel count over time, per source;
//   - fill overlays of a few keyframes, each named by its frame index and time;
//   - per-stage timings, the settings and the command that produced the run;
//   - links to the run's files, each with what it holds.
// Each Add* appends to an HtmlReport; hrefs are relative to the report's folder (`prefix` is the
// run folder seen from there: "" or "with_fill/").
#pragma once

#include <string>
#include <vector>

#include "acquisition/trajectory.h"
#include "pipeline/run_report.h"
#include "report/map_view.h"
#include "report/report_html.h"

namespace gf {

// The command line this process was started with, shell-quoted; set once by main().
void SetCommandLine(int argc, char** argv);
const std::string& CommandLine();

// A keyframe as a person reads it: "frame 60 (t = 1305031104.16 s)". `file` is an undistorted/
// image name (<index>_<ts>.png).
std::string FrameLabel(const std::string& file);

// The keyframes of a run as undistorted/ names them (<index>_<ts>.png), in frame order.
std::vector<std::string> KeyframeFiles(const std::string& run_dir);
// One line on what the run did, from its report.json (and the ATE when known, metres).
std::string RunSummaryText(const RunReport& report, const double* ate_m);

// The trajectory from above: the plane of the ground truth's (else the estimate's) two main
// directions of motion. `truth` may be empty.
void AddTrajectoryFigure(HtmlReport* r, const Trajectory& estimate, const Trajectory& truth);

// The surfel count over time of each run ("name" -> its report.json "surfels"), stable surfels.
void AddSurfelCountFigure(HtmlReport* r,
                          const std::vector<std::pair<std::string, SurfelReport>>& runs);

// Fill overlays of up to `count` keyframes spread over the run (from keyframes/).
void AddFillOverlays(HtmlReport* r, const std::string& run_dir, const std::string& prefix,
                     int count = 3);

void AddStageTimings(HtmlReport* r, const RunReport& report);

// The command and the settings (report.json "config") in collapsed blocks.
void AddSettings(HtmlReport* r, const RunReport& report);

// Links to the run folder's outputs that exist, with what each holds.
void AddFileLinks(HtmlReport* r, const std::string& run_dir, const std::string& prefix);

// RUN/report.html for `reconstruct`: every section above, for the run in run_dir whose report is
// `report` (its report.json; the page is written before it) and its input's groundtruth.txt,
// when there is one, for the ATE and the trajectory figure.
// `file` gives the paths of the files written beside it (the 3D view's scripts).
void WriteRunReport(const std::string& run_dir, const std::string& input,
                    const RunReport& report, const ReportFile& file);

}  // namespace gf
