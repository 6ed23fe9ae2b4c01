#include "pipeline/settings.h"

#include <gtest/gtest.h>

#include "acquisition/errors.h"
#include "pipeline/reconstruction.h"

namespace gf {
namespace {

// The problem InputError reports for `text`, or "" when ApplyConfig accepts it.
std::string Problem(const std::string& text, ReconstructionOptions* options) {
  try {
    ApplyConfig(text, "run.json", options);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "run.json");
    return e.problem();
  }
  return "";
}

TEST(Config, SettingsListEveryStageWithItsValues) {
  ReconstructionOptions options;
  options.fill_options.stereo.plane_sweep.max_planes = 64;
  const auto j = SettingsToJson(options);
  EXPECT_EQ(j["tracker"]["pyramid_levels"], 3);
  EXPECT_EQ(j["tracker"]["icp"]["iterations"].get<std::vector<int>>(),
            (std::vector<int>{10, 6, 2}));
  EXPECT_EQ(j["tracker"]["keyframes"]["max_translation_m"], 0.02);
  EXPECT_EQ(j["fill"]["pairs"]["min_matches"], 40);
  EXPECT_EQ(j["fill"]["pairs"]["refine"]["photometric"], true);
  EXPECT_EQ(j["fill"]["stereo"]["sgbm"]["block_size"], 5);
  EXPECT_EQ(j["fill"]["stereo"]["plane_sweep"]["max_planes"], 64);
  EXPECT_EQ(j["fill"]["carry"]["max_keyframes"], 15);
  EXPECT_EQ(j["fill"]["queue_capacity"], 16);
}

TEST(Config, OverridesWhatTheFileSetsAndKeepsTheRest) {
  ReconstructionOptions options;
  options.fill_options.stereo.plane_sweep_always = true;  // e.g. --sweep-all, not in the file
  EXPECT_EQ(Problem(R"({"tracker": {"icp": {"iterations": [8, 4]}, "pyramid_levels": 2},
                        "fill": {"stereo": {"sgbm": {"block_size": 7}, "photometric": {"min_ncc": 1},
                                            "plane_sweep": {"hole_windows": false}},
                                 "carry": {"agreement": 0.01}}})",
                    &options),
            "");
  EXPECT_EQ(options.tracker.icp.iterations, (std::vector<int>{8, 4}));
  EXPECT_EQ(options.tracker.pyramid_levels, 2);
  EXPECT_EQ(options.fill_options.stereo.sgbm.block_size, 7);
  EXPECT_EQ(options.fill_options.stereo.photometric.min_ncc, 1.0);  // an integer is a fine number
  EXPECT_FALSE(options.fill_options.stereo.plane_sweep.hole_windows);
  EXPECT_EQ(options.fill_options.carry.agreement, 0.01);
  EXPECT_TRUE(options.fill_options.stereo.plane_sweep_always);
  EXPECT_EQ(options.fill_options.stereo.sgbm.num_disparities, 128);
  EXPECT_EQ(options.tracker.icp.max_distance_m, 0.08);
}

TEST(Config, ARunsSettingsReadBackGiveTheSameSettings) {
  ReconstructionOptions changed;
  changed.tracker.use_features = false;
  changed.fill_options.pairs.lookahead = 4;
  changed.fill_options.stereo.validation.max_ring_error = 0.025;
  ReconstructionOptions read;
  EXPECT_EQ(Problem(SettingsToJson(changed).dump(), &read), "");
  EXPECT_EQ(SettingsToJson(read), SettingsToJson(changed));
}

TEST(Config, RefusesBadFilesAndLeavesTheOptionsAlone) {
  ReconstructionOptions options;
  const auto before = SettingsToJson(options);
  EXPECT_EQ(Problem(R"({"fill": {"stereo": {"blok_size": 5}}})", &options),
            "unknown setting 'fill.stereo.blok_size'");
  EXPECT_EQ(Problem(R"({"fill": {"stereo": {"sgbm": {"block_size": 5.5}}}})", &options),
            "'fill.stereo.sgbm.block_size' must be an integer");
  EXPECT_EQ(Problem(R"({"tracker": {"use_features": 1}})", &options),
            "'tracker.use_features' must be true or false");
  EXPECT_EQ(Problem(R"({"fill": {"carry": {"agreement": "2%"}}})", &options),
            "'fill.carry.agreement' must be a number");
  EXPECT_EQ(Problem(R"({"fill": {"stereo": 3}})", &options),
            "'fill.stereo' must be an object of settings");
  EXPECT_EQ(Problem(R"({"tracker": {"icp": {"iterations": []}}})", &options),
            "'tracker.icp.iterations' must be a non-empty list of integers");
  EXPECT_EQ(Problem(R"({"tracker": {"max_jump_m": null}})", &options),
            "'tracker.max_jump_m' must be a number");
  EXPECT_EQ(Problem("[1, 2]", &options), "the file must be an object of settings");
  EXPECT_EQ(Problem(R"({"fill": )", &options).rfind("not valid JSON", 0), 0u);
  // Values of the right kind that the options' Check() refuses.
  EXPECT_EQ(Problem(R"({"fill": {"stereo": {"sgbm": {"block_size": 4}}}})", &options),
            "settings refused (fill.stereo): block_size must be odd");
  // Two refusals: the first one's stage and message (the fill stage's own check, which also
  // refuses this search range, comes after the stereo's).
  EXPECT_EQ(Problem(R"({"fill": {"stereo": {"sgbm": {"block_size": 4, "num_disparities": 16}}}})",
                    &options),
            "settings refused (fill.stereo): block_size must be odd");
  // The fill stage's own check: pair selection's near disparity beyond SGBM's search.
  EXPECT_EQ(Problem(R"({"fill": {"pairs": {"max_near_disparity_px": 200}}})", &options),
            "settings refused (fill): pairs.max_near_disparity_px exceeds "
            "stereo.sgbm.num_disparities");
  // The old place of a setting is refused: the pair geometry is one setting, fill.geometry.
  EXPECT_EQ(Problem(R"({"fill": {"pairs": {"epipole_margin_px": 60}}})", &options),
            "unknown setting 'fill.pairs.epipole_margin_px'");
  EXPECT_EQ(SettingsToJson(options), before);
  EXPECT_EQ(Problem(R"({"fill": {"geometry": {"epipole_margin_px": 60}}})", &options), "");
  EXPECT_EQ(options.fill_options.Filler().pairs.geometry.epipole_margin_px, 60);
  EXPECT_EQ(options.fill_options.Filler().stereo.geometry.epipole_margin_px, 60);
}

TEST(Config, MissingFileIsAnInputError) {
  ReconstructionOptions options;
  EXPECT_THROW(ApplyConfigFile("/nonexistent/config.json", &options), InputError);
}

}  // namespace
}  // namespace gf
