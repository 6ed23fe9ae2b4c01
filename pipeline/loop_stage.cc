#include "pipeline/loop_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <mutex>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kRadPerDeg = M_PI / 180.0;

double Ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// A refusal's reason without its figures ("too few RANSAC inliers (3 of 20 needed)" -> "too few
// RANSAC inliers", "ICP moved RANSAC's pose by 0.05 m" -> "ICP moved RANSAC's pose"), so that
// reasons can be counted.
std::string ReasonKind(const std::string& reason) {
  size_t cut = reason.find_first_of("(:0123456789");
  std::string kind = reason.substr(0, cut);
  while (!kind.empty() && kind.back() == ' ') kind.pop_back();
  for (const std::string tail : {" by", " to"})
    if (kind.size() > tail.size() &&
        kind.compare(kind.size() - tail.size(), tail.size(), tail) == 0)
      kind.resize(kind.size() - tail.size());
  return kind;
}

}  // namespace

bool LoopStageOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.In("queue_capacity", queue_capacity, 1, kMaxFramesInMemory, kMoreFramesThanMemory)
      .Part("odometry_noise", odometry_noise)
      .Above("gap_sigma_m", gap_sigma_m, 0, kMaxSceneM, kLargerThanAnyScene)
      .Above("gap_sigma_deg", gap_sigma_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .In("relocalise_candidates", relocalise_candidates, 1, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .In("free_keyframes", free_keyframes, 1, kMaxCaptureFrames, kMoreFramesThanACapture)
      .Part("database", database)
      .Part("detector", detector)
      .Part("graph", graph);
  return c.ok();
}

LoopClosureStage::LoopClosureStage(const Camera& camera, const LoopStageOptions& options,
                                   PoseCorrections* corrections)
    : camera_(camera),
      options_(options),
      corrections_(corrections),
      queue_(options.queue_capacity),
      database_(options.database),
      detector_(camera, options.detector) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(corrections != nullptr, "the loop-closure stage publishes into PoseCorrections");
  worker_.Start("gf-loop", [this] { Run(); });
}

LoopClosureStage::~LoopClosureStage() {
  Cancel();
  worker_.Join();
}

bool LoopClosureStage::Offer(LoopKeyframeItem item) {
  const bool queued =
      options_.drop_when_busy ? queue_.TryPush(std::move(item)) : queue_.Push(std::move(item));
  if (!queued) ++dropped_;
  offered_ += queued;
  return queued;
}

void LoopClosureStage::Cancel() {
  cancelled_ = true;
  queue_.Close();
}

void LoopClosureStage::Finish(const std::function<bool()>& poll) {
  queue_.Close();
  while (!worker_.WaitFor(std::chrono::milliseconds(50)))
    if (poll && poll()) Cancel();
  worker_.Join();
  if (worker_.error()) std::rethrow_exception(worker_.error());
}

void LoopClosureStage::Run() {
  // However the worker ends, readers of the corrections stop waiting for it.
  struct Close {
    PoseCorrections* corrections;
    ~Close() { corrections->Close(); }
  } close{corrections_};
  LoopKeyframeItem item;
  while (!cancelled_ && queue_.Pop(&item)) {
    const auto start = Clock::now();
    try {
      Process(item);
    } catch (const std::exception& e) {
      ++failed_;
      spdlog::warn("loop closure: keyframe {} skipped: {}", KeyframeName(item.frame), e.what());
    }
    keyframe_ms_.push_back(Ms(start));
    corrections_->MarkProcessed(++keyframes_done_);
  }
  if (!cancelled_ && unoptimised_loops_) Optimise();
}

SE3 LoopClosureStage::AddNode(const LoopKeyframeItem& item, double scene_depth_m) {
  using Link = LoopKeyframeItem::Link;
  tracked_[item.id] = item.world_from_camera;
  PoseGraphEdge edge;
  edge.to = item.id;
  edge.from = item.linked_to;
  edge.from_from_to = item.linked_from_this;
  edge.information = AlignmentInformation(item.information, item.linked_from_this, scene_depth_m,
                                          options_.odometry_noise);
  edge.kind = item.link == Link::kRelocalised ? PoseGraphEdge::Kind::kRelocalisation
                                              : PoseGraphEdge::Kind::kOdometry;
  if (item.link == Link::kRestarted || (item.link != Link::kFirst && !graph_.HasNode(edge.from))) {
    // A guess (or the keyframe it follows was dropped): a weak link to the last node, at the
    // relative pose tracking assumed.
    edge.kind = PoseGraphEdge::Kind::kGap;
    edge.from = last_id_;
    if (edge.from >= 0)
      edge.from_from_to = tracked_.at(edge.from).Inverse() * item.world_from_camera;
    edge.information = InformationWithFloor(Matrix6d::Identity() * 1e12, options_.gap_sigma_m,
                                            options_.gap_sigma_deg * kRadPerDeg);
  }
  SE3 estimate = corrections_->Correction(item.id) * item.world_from_camera;
  if (item.link != Link::kFirst && edge.from >= 0)
    estimate = graph_.pose(edge.from) * edge.from_from_to;
  graph_.AddNode(item.id, estimate);
  if (item.link != Link::kFirst && edge.from >= 0) graph_.AddEdge(edge);
  last_id_ = item.id;
  return estimate;
}

void LoopClosureStage::Process(const LoopKeyframeItem& item) {
  std::shared_ptr<const LoopKeyframe> key =
      MakeLoopKeyframe(item.id, item.frame, item.world_from_camera, item.features);
  const SE3 estimate = AddNode(item, key->median_depth_m);
  const std::set<int> tied = graph_.NodesWithin(item.id, options_.detector.recent_keyframes);
  LoopDetection detection;
  {
    std::shared_lock<std::shared_mutex> lock(database_mutex_);
    detection = detector_.Detect(
        *key, estimate, database_, [&](int id) { return graph_.pose(id); },
        [&](int id) { return tied.count(id) != 0; });
  }
  bool stored_place = false;
  for (const PoseGraphEdge& e : detection.accepted) {
    graph_.AddEdge(e);
    tied_.insert({e.from, e.to});
    const double angle_deg =
        Eigen::AngleAxisd(e.from_from_to.RotationMatrix()).angle() / kRadPerDeg;
    stored_place |= e.from_from_to.translation().norm() <= options_.same_place.max_translation_m &&
                    angle_deg <= options_.same_place.max_rotation_deg;
  }
  if (stored_place) {
    ++same_place_;
  } else {
    std::unique_lock<std::shared_mutex> lock(database_mutex_);
    database_.Add(key);
  }
  Record(item, detection);
  if (!detection.accepted.empty()) {
    unoptimised_loops_ = true;
    Optimise();
  }
}

void LoopClosureStage::Optimise() {
  const PoseGraphSummary s = graph_.Optimize(options_.graph);
  ++optimisations_;
  optimise_ms_.push_back(s.ms);
  unoptimised_loops_ = false;
  spdlog::debug("loop closure: {}", s.BriefReport());
  if (!s.success) return;
  // Old keyframes that a loop the graph kept ties: held from now on (free_keyframes).
  const int newest_free = last_id_ - options_.free_keyframes;
  std::set<int> kept;
  for (const PoseGraphEdge& e : graph_.edges())
    if (e.kind == PoseGraphEdge::Kind::kLoop && !e.rejected) kept.insert({e.from, e.to});
  for (auto it = tied_.begin(); it != tied_.end() && *it < newest_free; it = tied_.erase(it))
    if (kept.count(*it)) graph_.Hold(*it);
  std::map<int, SE3> corrections;
  for (const auto& [id, pose] : graph_.poses()) corrections[id] = pose * tracked_.at(id).Inverse();
  corrections_->Publish(std::move(corrections));
}

void LoopClosureStage::Record(const LoopKeyframeItem& item, const LoopDetection& detection) {
  spdlog::debug("loop closure {}: {}", KeyframeName(item.frame), detection.BriefReport());
  for (const LoopCandidate& c : detection.candidates) {
    ++candidates_;
    verified_ += c.verification.success;
    if (c.outcome == "pending") {
      ++pending_;
    } else if (c.outcome != "accepted") {
      ++refused_[ReasonKind(c.outcome)];
    }
  }
  const std::string name = KeyframeName(item.frame);
  for (const PoseGraphEdge& e : detection.accepted) {
    if (accepted_.size() >= 500) break;  // the report lists the first ones
    const auto other = database_.Find(e.from);
    accepted_.push_back(
        {name, other ? other->name : std::to_string(e.from), detection.consistent_correction});
  }
}

std::optional<Relocalisation> LoopClosureStage::Relocalise(const RgbdFrame& frame,
                                                           const FrameFeatures& features) {
  ++relocalisation_attempts_;
  if (features.empty()) return std::nullopt;
  // Recorded input: against every keyframe offered before this frame, however far the loop
  // thread has got (the same answer every run).
  if (!options_.drop_when_busy) {
    int version = 0;
    corrections_->AtProcessed(offered_, &version, [&] { return cancelled_.load(); });
  }
  const auto query = MakeLoopKeyframe(-1, frame, SE3(), std::make_shared<FrameFeatures>(features));
  std::shared_lock<std::shared_mutex> lock(database_mutex_);
  std::vector<int> ids;
  for (const auto& m : database_.QueryAppearance(
           features.descriptors, options_.relocalise_candidates, [](int) { return true; }))
    ids.push_back(m.id);
  // The newest keyframes too: the vocabulary may not exist yet, and loss is often brief.
  const auto& all = database_.keyframes();
  for (size_t i = all.size() > 2 ? all.size() - 2 : 0; i < all.size(); ++i)
    if (std::find(ids.begin(), ids.end(), all[i]->id) == ids.end()) ids.push_back(all[i]->id);
  for (int id : ids) {
    const auto candidate = database_.Find(id);
    const LoopVerification v =
        VerifyLoop(*query, *candidate, camera_, options_.detector.verification);
    spdlog::debug("relocalisation of {} against {}: {}", KeyframeName(frame), candidate->name,
                  v.BriefReport());
    if (!v.success) continue;
    Relocalisation r;
    r.keyframe = id;
    r.keyframe_from_camera = v.candidate_from_query;
    r.information = v.icp.information;
    // In tracking's own frame: where the candidate was tracked.
    r.world_from_camera = candidate->world_from_camera * v.candidate_from_query;
    ++relocalised_;
    return r;
  }
  return std::nullopt;
}

LoopReport LoopClosureStage::Report() const {
  LoopReport r;
  r.enabled = true;
  for (const PoseGraphEdge& e : graph_.edges()) {
    r.accepted += e.kind == PoseGraphEdge::Kind::kLoop;
    r.rejected_by_graph += e.rejected;
  }
  r.refused = refused_;
  std::shared_lock<std::shared_mutex> lock(database_mutex_);
  r.keyframes = keyframes_done_.load();
  r.keyframes_dropped = dropped_.load();
  r.keyframes_stored = static_cast<int>(database_.keyframes().size());
  r.keyframes_same_place = same_place_;
  r.keyframes_held = graph_.held_count();
  r.keyframes_failed = failed_;
  r.candidates = candidates_;
  r.verified = verified_;
  r.pending_when_seen = pending_;
  r.optimisations = optimisations_;
  r.optimisation_ms = StepTimes::Of(optimise_ms_);
  r.keyframe_ms = StepTimes::Of(keyframe_ms_);
  r.relocalisation_attempts = relocalisation_attempts_.load();
  r.relocalised = relocalised_.load();
  r.database_bytes = database_.MemoryBytes();
  r.loops = accepted_;
  return r;
}

}  // namespace gf
