#include "pipeline/settings.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

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

// Every setting in the tree, changed on its own to another value its check accepts, is read
// back by --config (ApplyConfig) and written again by --print-config (SettingsToJson) as given:
// no setting is written without being read, or read into another field.
TEST(Config, EverySettingRoundTripsOnItsOwn) {
  const nlohmann::json defaults = nlohmann::json::parse(SettingsToJson({}).dump());
  const nlohmann::json leaves = defaults.flatten();  // {"/tracker/pyramid_levels": 3, ...}
  int settings = 0;
  for (const auto& leaf : leaves.items()) {
    const nlohmann::json::json_pointer place(leaf.key());
    const nlohmann::json& value = leaf.value();
    // Candidate changes, tried in turn until one is accepted.
    std::vector<nlohmann::json> changes;
    if (value.is_boolean()) {
      changes = {!value.get<bool>()};
    } else if (value.is_number_integer()) {
      const long v = value.get<long>();
      changes = {v + 2, v + 1, v - 1, v * 2};
    } else if (value.is_number()) {
      // Powers of two and their multiples: exact in a float field too.
      const double v = value.get<double>();
      changes = {v * 2, v * 0.5, 0.5, 1.0, 2.0, 0.25};
    } else if (value.is_string()) {
      changes = {"bottom_to_top", "top_to_bottom"};
    }
    SCOPED_TRACE(leaf.key());
    ASSERT_FALSE(changes.empty()) << "a setting of an unexpected kind: " << value;
    bool round_trips = false;
    for (const nlohmann::json& change : changes) {
      if (change == value) continue;
      nlohmann::json expected = defaults;
      expected[place] = change;
      // An element of a list is given as the whole list (a file replaces lists whole).
      const nlohmann::json::json_pointer given_place =
          defaults[place.parent_pointer()].is_array() ? place.parent_pointer() : place;
      nlohmann::json given = nlohmann::json::object();
      given[given_place] = expected[given_place];
      ReconstructionOptions read;
      if (!Problem(given.dump(), &read).empty()) continue;  // outside its bounds: the next one
      // Empty when the tree read back is the one given; else the JSON Patch from one to the other.
      const nlohmann::json difference =
          nlohmann::json::diff(expected, nlohmann::json::parse(SettingsToJson(read).dump()));
      EXPECT_TRUE(difference.empty()) << difference.dump();
      round_trips = true;
      break;
    }
    EXPECT_TRUE(round_trips) << "no change of " << value << " was accepted";
    ++settings;
  }
  EXPECT_GT(settings, 100);
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
            "fill.stereo.sgbm.block_size must be odd");
  // Two refusals: the first one's setting and message (the fill stage's own check, which also
  // refuses this search range, comes after the stereo's).
  EXPECT_EQ(Problem(R"({"fill": {"stereo": {"sgbm": {"block_size": 4, "num_disparities": 16}}}})",
                    &options),
            "fill.stereo.sgbm.block_size must be odd");
  // The fill stage's own check: pair selection's near disparity beyond SGBM's search.
  EXPECT_EQ(Problem(R"({"fill": {"pairs": {"max_near_disparity_px": 200}}})", &options),
            "fill.pairs.max_near_disparity_px exceeds stereo.sgbm.num_disparities");
  // The old place of a setting is refused: the pair geometry is one setting, fill.geometry.
  EXPECT_EQ(Problem(R"({"fill": {"pairs": {"epipole_margin_px": 60}}})", &options),
            "unknown setting 'fill.pairs.epipole_margin_px'");
  // A closed set: a name outside it is refused, not read as its first value.
  EXPECT_EQ(Problem(R"({"tracker": {"depth_readout_order": "diagonal"}})", &options),
            "bad setting: tracker.depth_readout_order must be top_to_bottom, bottom_to_top, "
            "left_to_right or right_to_left, not \"diagonal\"");
  EXPECT_EQ(SettingsToJson(options), before);
  EXPECT_EQ(Problem(R"({"fill": {"geometry": {"epipole_margin_px": 60}}})", &options), "");
  EXPECT_EQ(Problem(R"({"tracker": {"depth_readout_order": "right_to_left"}})", &options), "");
  EXPECT_EQ(options.tracker.depth_readout_order, ReadoutOrder::kRightToLeft);
  EXPECT_EQ(SettingsToJson(options)["tracker"]["depth_readout_order"], "right_to_left");
  EXPECT_EQ(options.fill_options.Filler().pairs.geometry.epipole_margin_px, 60);
  EXPECT_EQ(options.fill_options.Filler().stereo.geometry.epipole_margin_px, 60);
}

// Values beyond a bound with a meaning are refused, naming the setting by its place in the tree.
TEST(Config, RefusesValuesBeyondTheirBoundsNamingTheSetting) {
  ReconstructionOptions options;
  EXPECT_EQ(Problem(R"({"fusion": {"normal_filter_px": 30000}})", &options),
            "fusion.normal_filter_px 30000 is larger than any half-size image (at most "
            "2048)");
  EXPECT_EQ(Problem(R"({"fill": {"pairs": {"refine": {"photometric_iterations": [100000, 7]}}}})",
                    &options),
            "fill.pairs.refine.photometric_iterations[0] 100000 is more iterations than a "
            "frame's time allows (at most 1000)");
  EXPECT_EQ(Problem(R"({"fusion": {"max_surfels": 2000000000}})", &options),
            "fusion.max_surfels 2000000000 takes more than the map's 16 GiB at 48 bytes "
            "a surfel (at most 357913941)");
  EXPECT_EQ(Problem(R"({"tracker": {"icp": {"max_distance_m": -1}}})", &options),
            "tracker.icp.max_distance_m -1 must be more than 0");
  EXPECT_EQ(Problem(R"({"loop_closure": {"detector": {"verification": {"noise": {"bias": 50}}}}})",
                    &options)
                .rfind("loop_closure.detector.verification.noise.bias 50 ", 0),
            0u);
  // An integer beyond an int would wrap when read: refused before.
  EXPECT_EQ(Problem(R"({"fusion": {"pixel_step": 4294967297}})", &options),
            "'fusion.pixel_step' 4294967297 is beyond any integer setting");
  // A number beyond a double is no valid JSON number for us either (nlohmann: out_of_range).
  EXPECT_EQ(Problem(R"({"tracker": {"max_jump_m": 1e400}})", &options).rfind("not valid JSON", 0),
            0u);
  EXPECT_EQ(SettingsToJson(options), SettingsToJson(ReconstructionOptions()));
}

// Every number in the settings tree has an upper bound: set to 1e12 (integers to 2e9, lists'
// elements too) it is refused, and the message names it. No setting is exempt.
TEST(Config, EveryNumericSettingHasAnUpperBound) {
  const nlohmann::json tree = nlohmann::json::parse(SettingsToJson(ReconstructionOptions()).dump());
  std::vector<std::pair<std::string, nlohmann::json::json_pointer>> numbers;
  std::function<void(const nlohmann::json&, const nlohmann::json::json_pointer&, std::string)>
      walk = [&](const nlohmann::json& j, const nlohmann::json::json_pointer& at,
                 const std::string& name) {
        if (j.is_object()) {
          for (const auto& [key, value] : j.items())
            walk(value, at / key, name.empty() ? key : name + "." + key);
        } else if (j.is_array()) {
          for (size_t i = 0; i < j.size(); ++i) walk(j[i], at / i, name);
        } else if (j.is_number()) {
          numbers.emplace_back(name, at);
        }
      };
  walk(tree, nlohmann::json::json_pointer(), "");
  EXPECT_GT(numbers.size(), 150u);  // the tree holds about 170 numbers
  for (const auto& [name, at] : numbers) {
    nlohmann::json changed = tree;
    const bool integer = tree[at].is_number_integer();
    changed[at] = integer ? nlohmann::json(2'000'000'000) : nlohmann::json(1e12);
    ReconstructionOptions options;
    const std::string problem = Problem(changed.dump(), &options);
    EXPECT_NE(problem.find(name), std::string::npos)
        << name << " = " << changed[at] << ": " << (problem.empty() ? "accepted" : problem);
  }
}

TEST(Config, MissingFileIsAnInputError) {
  ReconstructionOptions options;
  EXPECT_THROW(ApplyConfigFile("/nonexistent/config.json", &options), InputError);
}

// The map's settings moved from fusion.fusion.X to fusion.X: the old place is still read (with a
// warning), and the new one wins where a file gives both.
TEST(Config, ReadsTheMapsSettingsAtTheirOldPlace) {
  ReconstructionOptions options;
  EXPECT_EQ(Problem(R"({"fusion": {"fusion": {"max_surfels": 1000, "pixel_step": 3}}})", &options),
            "");
  EXPECT_EQ(options.fusion_options.fusion.max_surfels, 1000);
  EXPECT_EQ(options.fusion_options.fusion.pixel_step, 3);
  EXPECT_EQ(Problem(R"({"fusion": {"pixel_step": 2, "fusion": {"pixel_step": 5}}})", &options), "");
  EXPECT_EQ(options.fusion_options.fusion.pixel_step, 2);
  EXPECT_EQ(Problem(R"({"fusion": {"fusion": {"normal_filter_px": 30000}}})", &options),
            "fusion.normal_filter_px 30000 is larger than any half-size image (at most 2048)");
  const nlohmann::ordered_json tree = SettingsToJson(options);
  EXPECT_FALSE(tree["fusion"].contains("fusion"));
  EXPECT_EQ(tree["fusion"]["max_surfels"], 1000);
}

}  // namespace
}  // namespace gf
