#include "report/run_report.h"

#include <gtest/gtest.h>

namespace gf {
namespace {

RunReport FilledRun() {
  RunReport r;
  r.complete = true;
  r.frames = 30;
  r.seconds = 6;
  r.fps = 5;
  r.keyframes = 10;
  r.tracking.lost_frames = 1;
  r.loops.enabled = true;
  r.loops.accepted = 2;
  KeyframeFill k;
  k.timestamp = "1.0";
  k.hole_pixels = 200;
  k.filled_pixels = 150;
  r.fill = FillReport::Of({k}, 0, 0);
  r.surfels = SurfelReport();
  r.surfels->count = 1234;
  r.surfels->by_source = {{"sensor", 1000}, {"stereo_fill", 234}};
  r.stages.steps = {{"read", StepTimes::Of({2, 4})}, {"stereo", StepTimes::Of({})}};
  r.config.hardware_concurrency = 2;
  return r;
}

// The page's summary line reads the report's figures; a section the run did not have is left
// out of it.
TEST(RunReportPage, TheSummarySaysWhatTheRunDid) {
  const RunReport r = FilledRun();
  const double ate_m = 0.0123;
  const std::string text = RunSummaryText(r, &ate_m);
  EXPECT_NE(text.find("30 frames in 6.0 s (5.0 fps"), std::string::npos) << text;
  EXPECT_NE(text.find("1 frames lost"), std::string::npos) << text;
  EXPECT_NE(text.find("2 loops accepted"), std::string::npos) << text;
  EXPECT_NE(text.find("75.0% of the keyframes' hole pixels filled"), std::string::npos) << text;
  EXPECT_NE(text.find("1234 surfels (234 from the fill)"), std::string::npos) << text;
  EXPECT_NE(text.find("(ATE) 1.23 cm"), std::string::npos) << text;
  RunReport bare = r;
  bare.loops = LoopReport();
  bare.fill.reset();
  bare.surfels.reset();
  const std::string plain = RunSummaryText(bare, nullptr);
  EXPECT_EQ(plain.find("loops"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("filled"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("surfels"), std::string::npos) << plain;
}

// Stages that ran are listed with their times; a stage without steps is left out.
TEST(RunReportPage, StageTimesListTheStagesThatRan) {
  HtmlReport page("test");
  AddStageTimings(&page, FilledRun());
  const std::string html = page.Html();
  EXPECT_NE(html.find("reading and decoding a frame"), std::string::npos);
  EXPECT_NE(html.find("4.0"), std::string::npos);  // the upper median and the max of {2, 4}
  EXPECT_EQ(html.find("stereo fill of a keyframe"), std::string::npos);
  EXPECT_NE(html.find("on 2 cores"), std::string::npos);
}

}  // namespace
}  // namespace gf
