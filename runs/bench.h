// `glassfusion bench INPUT`: GlassFusion's tracker and OpenCV's RGB-D odometry peers on the same
// frames in one run: per-frame time, frames per second (with the machine's core count) and, when
// ground truth sits beside the input (groundtruth.txt / groundtruth.log) or is given, ATE.
//
// Frames are decoded into memory first, so only tracking is timed. The OpenCV peers (RgbdOdometry,
// ICPOdometry, RgbdICPOdometry, FastICPOdometry from opencv_contrib's rgbd module, Debian's build)
// run frame-to-frame with their default parameters and our camera matrix, chaining
// world_from_current = world_from_previous * Rt^-1 (OpenCV's Rt maps source points to the
// destination frame). A peer that fails on a frame keeps its previous pose there, as ours does.
//
// With fill_every, the keyframe fill that the pipeline runs (fill/keyframe_filler.h: pair
// selection, FillHolesByStereo, the carry) is timed per keyframe with OpenCV held to one thread:
// the "time per keyframe pair on one core" figure.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/frame_source.h"
#include "pipeline/reconstruction.h"
#include "registration/tracker.h"

namespace gf {

struct BenchOptions {
  std::string input;
  std::string gt;  // ground truth; "" = INPUT/groundtruth.txt or .log when present
  int first_frame = 0;
  int end_frame = -1;
  bool peers = true;  // also run the OpenCV odometry peers
  // Also the whole tracking pipeline with loop closure (in-process, its stage threads, no fill
  // or fusion): ATE beside the others, and the loop stage's cost per keyframe.
  bool loop_closure = true;
  // Also the whole reconstruction as `reconstruct` runs it (fill, fusion, loop closure, the map's
  // completion; outputs in memory): end-to-end frames per second, CPU seconds per stage, the
  // cores used and the peak memory the run added.
  bool end_to_end = true;
  // > 0: also time stereo hole filling on one core, with every fill_every-th frame a keyframe,
  // paired and filled as reconstruct does (KeyframePairScheduler, then FillHolesByStereo) with our
  // tracked poses; next to OpenCV's StereoSGBM alone on the same rectified sideways pairs.
  int fill_every = 0;
  // Also time the surfel fusion per frame, on one core and on two, with our tracked poses, and
  // with a map of about a million surfels (runs/bench_fusion.h).
  bool fusion = false;
  // Also our tracker refined against the surfel map (frame-to-model), fused as it goes.
  bool frame_to_model = false;
  FrameSourceOptions source;
  // Ours, as reconstruct runs them (--config FILE may change them): the tracker, the fill (pairs,
  // stereo, also the OpenCV SGBM peer's settings, carry) and the fusion.
  ReconstructionOptions pipeline;
  bool Check(std::string* message = nullptr) const;
};

// Returns the JSON printed by the command: one entry per method.
nlohmann::ordered_json RunBench(const BenchOptions& options);

}  // namespace gf
