// The comparison of two maps (`glassfusion compare`: with and without the stereo fill) as report
// sections, shared by compare's DIR/report.html and the demo's page.
#pragma once

#include <string>

#include "report/map_view.h"
#include "report/report_html.h"

namespace gf {

// The comparison in DIR = out_dir (as RunCompare wrote it: compare.json, with_fill/, without_fill/,
// the renderings) as report sections: both maps rendered from the same viewpoints and in 3D,
// completeness and accuracy against ground truth, both maps' size over time, the trajectory, fill
// overlays, timings, settings and links. `prefix` is DIR seen from the report's folder ("" for
// DIR/report.html); `file` gives the paths of files written beside the report (the 3D view).
void AddComparisonSections(HtmlReport* r, const std::string& out_dir, const std::string& prefix,
                           const ReportFile& file);

}  // namespace gf
