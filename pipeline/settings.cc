#include "pipeline/settings.h"

#include <spdlog/spdlog.h>

#include <cstdint>
#include <limits>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace gf {

// A closed set as its name; a name outside it is refused (nlohmann's NLOHMANN_JSON_SERIALIZE_ENUM
// would read it silently as the first value).
void to_json(nlohmann::json& j, ReadoutOrder order) { j = ReadoutOrderName(order); }
void from_json(const nlohmann::json& j, ReadoutOrder& order) {
  if (!j.is_string() || !ParseReadoutOrder(j.get<std::string>(), &order))
    throw std::invalid_argument(
        "tracker.depth_readout_order must be top_to_bottom, bottom_to_top, left_to_right or "
        "right_to_left, not " + j.dump());
}

// JSON conversions of the Options structs, field by field (nlohmann's macros). They live here, at
// the command line's edge, so that the algorithms' headers stay free of JSON.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(IcpOptions, iterations, max_distance_m, max_normal_angle_deg,
                                   plane_sigma_m, depth_weighting, noise_a_m, noise_b_per_m,
                                   plane_huber, feature_sigma_px, feature_huber, feature_weight,
                                   feature_min_level, min_inliers, max_rmse_m, convergence_step)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SurfOptions, hessian_threshold, octaves, initial_step, upright,
                                   max_features)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MatchOptions, ratio, cross_check, same_laplacian)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RansacOptions, inlier_threshold_m, confidence, max_iterations,
                                   min_inliers)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(KeyframePolicy, max_rotation_deg, max_translation_m, min_overlap,
                                   min_feature_inliers)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(TrackerOptions, pyramid_levels, icp, use_features, surf, match,
                                   ransac, restart_m, restart_deg, keyframes, constant_velocity,
                                   max_jump_m, max_jump_deg, relocalise_frames,
                                   simulated_drift_deg_per_m, depth_readout_s, depth_readout_order)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PoseRefinementOptions, reprojection_px, min_inliers,
                                   max_change_m, max_change_deg, photometric,
                                   photometric_iterations)
// The pair geometry appears once, at fill.geometry (FillStageOptions::Filler copies it).
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PairGeometryOptions, min_baseline_m, epipole_margin_px)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PairSelectionOptions, min_matches, max_evaluations,
                                   max_baseline_m, min_median_disparity_px, max_near_disparity_px,
                                   max_near_disparity_sweep_px, allow_forward, max_rotation_deg,
                                   window, lookahead, spread_third_view_forward,
                                   mirror_third_view_sideways, max_witnesses, surf, match, refine)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PlaneSweepOptions, window_px, max_planes, max_step_px, min_ncc,
                                   min_uniqueness, min_parallax_px, min_texture, min_window_inside,
                                   smooth_small, smooth_large, downscale, textureless_cost,
                                   context_px, hole_windows)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SgbmOptions, num_disparities, rectify_alpha, max_zoom,
                                   min_valid_fraction, block_size, uniqueness_ratio,
                                   speckle_window, speckle_range, max_lr_difference_px)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DepthStepOptions, jump, far_side_px, near_side_px)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SeeThroughOptions, ratio, rim_px, near_side_px)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ValidationOptions, min_depth_m, max_depth_m, ring_px,
                                   min_ring_samples, ring_cell_px, max_ring_error,
                                   ring_scale_correction, max_ring_scale, max_pair_error,
                                   free_space_check, free_space_margin)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PhotometricOptions, patch_px, hole_patches, min_ncc,
                                   min_patch_std, max_mean_difference, occlusion_margin,
                                   corroboration_depth_step, corroboration_shift_px)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(StereoFillOptions, plane_sweep_forward, plane_sweep_always,
                                   plane_sweep_after_sgbm, sweep_sgbm_rejects, sweep_shadows, sgbm,
                                   plane_sweep, depth_steps, see_through, validation, photometric)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(FillCarryOptions, max_keyframes, min_agreeing, agreement,
                                   correct_own_fills)

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RevolutionOptions, enabled, cluster_gap_m, min_surfels,
                                   max_axis_spread, min_radius_m, max_radius_m, max_residual_m,
                                   max_normal_angle_deg, max_residual_share, min_arc_deg,
                                   height_step_m, spacing_m, stand_on_support, fit_whole_surface, support_radius_m,
                                   support_inlier_m, min_support_share, min_support_angle_deg,
                                   max_base_gap_m, fit_outline, outline_views, min_edge_ratio)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(GlassOptions, enabled, min_readings_on, min_through_share,
                                   edge_margin_px, stable_confidence, revolution)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(FusionOptions, min_depth_m, max_depth_m, pixel_step,
                                   fill_pixel_step, max_depth_gap_m, max_normal_angle_deg,
                                   normal_test_min_facing, max_radius_ratio, confidence_sigma,
                                   stable_confidence, unstable_frames, fill_weight,
                                   fill_stable_confidence, confirm_fills_across_keyframes,
                                   confirm_corroborated_fills, fill_unstable_frames,
                                   free_space_margin, free_space_penalty, max_neighbour_step,
                                   merge_copies_every, normal_filter_px, normal_filter_depth_m,
                                   normal_baseline_px, max_surfels)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(KeyframeDatabaseOptions, words, vocabulary_keyframes,
                                   kmeans_iterations)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(AlignmentNoise, floor_m, floor_deg, bias)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(LoopVerificationOptions, match, ransac, min_inlier_ratio,
                                   min_spread_m, icp, min_overlap, max_refine_m, max_refine_deg,
                                   max_sigma_m, noise)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(LoopDetectorOptions, recent_keyframes, appearance_candidates,
                                   min_appearance_score, proximity_candidates, proximity_m,
                                   proximity_deg, verification, confirm_m, confirm_deg,
                                   min_consistent)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PoseGraphOptions, max_loop_chi2, loop_huber, max_iterations,
                                   max_rejections)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(LoopStageOptions, database, detector, graph, queue_capacity,
                                   odometry_noise, gap_sigma_m, gap_sigma_deg,
                                   relocalise_candidates, free_keyframes)
// The stage's own settings; its map's (FusionOptions) stand beside them under "fusion"
// (SettingsTree, ApplyConfig: their names differ), the glass settings at "glass".
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(FusionStageOptions, queue_capacity, count_every, fuse_carried,
                                   complete_keyframes, completion_max_gap_px,
                                   completion_max_angle_deg, completion_min_support,
                                   completion_occluder_px, completion_support_half)

namespace {

// "fusion": the stage's settings and its map's, side by side.
nlohmann::json FusionTree(const FusionStageOptions& o) {
  nlohmann::json tree = o;
  tree.update(nlohmann::json(o.fusion));
  return tree;
}

// Every setting, as a config file gives them (keys sorted).
nlohmann::json SettingsTree(const ReconstructionOptions& o) {
  const FillStageOptions& fill = o.fill_options;
  return {{"tracker", o.tracker},
          {"fill",
           {{"queue_capacity", fill.queue_capacity},
            {"geometry", fill.geometry},
            {"pairs", fill.pairs},
            {"stereo", fill.stereo},
            {"carry", fill.carry}}},
          {"fusion", FusionTree(o.fusion_options)},
          {"glass", o.fusion_options.fusion.glass},
          {"loop_closure", o.loop_options}};
}

bool FitsAnInt(const nlohmann::json& value) {
  if (value.is_number_unsigned())
    return value.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<int>::max());
  const int64_t v = value.get<int64_t>();
  return v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max();
}

// Checks `given` (the file's tree) against `known` (every setting, current values): same keys,
// objects where objects are, and values of the same kind. `where` is the dotted path so far.
void CheckAgainst(const nlohmann::json& given, const nlohmann::json& known,
                  const std::string& where, const std::string& path) {
  const std::string name = where.empty() ? "the file" : "'" + where + "'";
  if (known.is_object()) {
    if (!given.is_object()) throw InputError(path, name + " must be an object of settings");
    for (const auto& [key, value] : given.items()) {
      const std::string child = where.empty() ? key : where + "." + key;
      if (!known.contains(key)) throw InputError(path, "unknown setting '" + child + "'");
      CheckAgainst(value, known.at(key), child, path);
    }
  } else if (known.is_boolean()) {
    if (!given.is_boolean()) throw InputError(path, name + " must be true or false");
  } else if (known.is_number_integer()) {
    if (!given.is_number_integer()) throw InputError(path, name + " must be an integer");
    // Integer settings are ints (max_surfels' bound fits one too): a larger number would wrap.
    if (!FitsAnInt(given))
      throw InputError(path, name + " " + given.dump() + " is beyond any integer setting");
  } else if (known.is_number()) {
    if (!given.is_number()) throw InputError(path, name + " must be a number");
  } else if (known.is_array()) {
    if (!given.is_array() || given.empty())
      throw InputError(path, name + " must be a non-empty list of integers");
    for (const auto& v : given)
      if (!v.is_number_integer() || !FitsAnInt(v))
        throw InputError(path, name + " must be a non-empty list of integers");
  }
}

// Settings that moved, read at their old place for one release with a warning: "fusion.fusion.X"
// (the map's settings) is "fusion.X" since 2026-12-07. A key given at both places keeps the new
// one's value.
void MoveOldKeys(const std::string& path, nlohmann::json* given) {
  if (!given->is_object() || !given->contains("fusion") || !(*given)["fusion"].is_object())
    return;
  nlohmann::json& fusion = (*given)["fusion"];
  if (!fusion.contains("fusion") || !fusion["fusion"].is_object()) return;
  const nlohmann::json old = fusion["fusion"];
  fusion.erase("fusion");
  for (const auto& [key, value] : old.items())
    if (!fusion.contains(key)) fusion[key] = value;
  spdlog::warn("{}: settings under \"fusion\": {{\"fusion\": ...}} are now directly under "
               "\"fusion\" (fusion.fusion.X is fusion.X); the old place is read until the next "
               "release",
               path);
}

}  // namespace

nlohmann::ordered_json SettingsToJson(const ReconstructionOptions& options) {
  // Through nlohmann::json (keys sorted) into an ordered_json for report.json.
  return nlohmann::ordered_json::parse(SettingsTree(options).dump());
}

void ApplyConfig(const std::string& text, const std::string& path, ReconstructionOptions* options) {
  nlohmann::json given;
  try {
    given = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for a number beyond a double (1e400).
    throw InputError(path, std::string("not valid JSON: ") + e.what());
  }
  MoveOldKeys(path, &given);
  nlohmann::json merged = SettingsTree(*options);
  CheckAgainst(given, merged, "", path);
  merged.merge_patch(given);
  ReconstructionOptions o = *options;
  FillStageOptions& f = o.fill_options;
  try {
    merged.at("tracker").get_to(o.tracker);
    const nlohmann::json& fill = merged.at("fill");
    fill.at("queue_capacity").get_to(f.queue_capacity);
    fill.at("geometry").get_to(f.geometry);
    fill.at("pairs").get_to(f.pairs);
    fill.at("stereo").get_to(f.stereo);
    fill.at("carry").get_to(f.carry);
    merged.at("fusion").get_to(o.fusion_options);
    merged.at("fusion").get_to(o.fusion_options.fusion);
    merged.at("glass").get_to(o.fusion_options.fusion.glass);
    merged.at("loop_closure").get_to(o.loop_options);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("bad setting: ") + e.what());
  } catch (const std::invalid_argument& e) {  // a name outside its closed set
    throw InputError(path, std::string("bad setting: ") + e.what());
  }
  // In order, stopping at the first refusal: its message, which starts with the field's name
  // within the part, is the one reported after the part's place in the tree.
  std::string problem;
  auto refuse = [&](const char* name) {
    throw InputError(path, std::string(name) + "." + problem);
  };
  if (!o.tracker.Check(&problem)) refuse("tracker");
  if (!f.geometry.Check(&problem)) refuse("fill.geometry");
  if (!f.pairs.Check(&problem)) refuse("fill.pairs");
  if (!f.stereo.Check(&problem)) refuse("fill.stereo");
  if (!f.carry.Check(&problem)) refuse("fill.carry");
  if (!f.Check(&problem)) refuse("fill");
  if (!o.fusion_options.fusion.glass.Check(&problem)) refuse("glass");
  if (!o.fusion_options.fusion.Check(&problem)) refuse("fusion");  // the map's, at fusion.X
  if (!o.fusion_options.Check(&problem)) refuse("fusion");
  if (!o.loop_options.Check(&problem)) refuse("loop_closure");
  *options = o;
}

void ApplyConfigFile(const std::string& path, ReconstructionOptions* options) {
  ApplyConfig(ReadTextFile(path), path, options);
}

}  // namespace gf
