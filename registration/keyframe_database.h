// The keyframes loop closure and relocalisation search: each keyframe's SURF features (the ones
// tracking computed), its depth at half resolution (for the geometric verification, loop_detector.h)
// and its tracked pose; and an index over their descriptors for place recognition.
//
// Place recognition by appearance, a bag of visual words (Sivic and Zisserman's "Video Google";
// DBoW's scoring): a flat vocabulary of words is clustered by k-means from the descriptors of the
// capture's first keyframes, each keyframe becomes a histogram of its descriptors' nearest words
// weighted by tf-idf (idf from those first keyframes) and normalised to sum 1, and two keyframes
// score the intersection of their histograms (0: no word in common, 1: the same). An inverted
// index (word -> keyframes) makes a query cost the words it shares, not the database's size.
// Chosen over a vocabulary trained beforehand (DBoW2's) because Debian has none and one trained on
// other scenes would be a data file of its own; and over an index of every descriptor (FLANN k-d
// trees) because those cannot grow: rebuilding them took 1.1 s for 150,000 descriptors (300
// keyframes) on this project's 2-core machine. Keyframes added before the vocabulary exists are
// described once it does.
//
// No threads, no I/O; not thread-safe (the loop-closure stage guards it).
//
// Usage:
//   gf::KeyframeDatabase db({});
//   db.Add(gf::MakeLoopKeyframe(id, frame, world_from_camera, features));
//   for (const auto& m : db.QueryAppearance(features.descriptors, 3, allowed)) ...
#pragma once

#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/rgbd_frame.h"
#include "acquisition/se3.h"
#include "registration/frame_features.h"

namespace gf {

// A keyframe as loop closure keeps it.
struct LoopKeyframe {
  int id = 0;                 // the tracker's keyframe number
  std::string name;           // its timestamp as the input lists it (for reports)
  SE3 world_from_camera;      // as tracked (the odometry frame)
  std::shared_ptr<const FrameFeatures> features;
  cv::Mat depth;              // CV_16U millimetres at half resolution (0 = none)
  double median_depth_m = 0;  // of its measured pixels
};

// Keeps the frame's depth at half resolution (nearest pixel: no blending across edges).
std::shared_ptr<const LoopKeyframe> MakeLoopKeyframe(int id, const RgbdFrame& frame,
                                                     const SE3& world_from_camera,
                                                     std::shared_ptr<const FrameFeatures> features);

struct KeyframeDatabaseOptions {
  // Visual words in the vocabulary (fewer if few descriptors); at most an image's pixels.
  int words = 500;
  int vocabulary_keyframes = 10;   // the first keyframes, whose descriptors train it
  int kmeans_iterations = 10;      // Lloyd iterations of the clustering (k-means++ seeding)
  // Each field within its range, upper bounds as acquisition/bounds.h explains them; the message
  // names the field (a part's field as part.field).
  bool Check(std::string* message = nullptr) const;
};

class KeyframeDatabase {
 public:
  explicit KeyframeDatabase(const KeyframeDatabaseOptions& options);
  ~KeyframeDatabase();
  KeyframeDatabase(const KeyframeDatabase&) = delete;
  KeyframeDatabase& operator=(const KeyframeDatabase&) = delete;

  void Add(std::shared_ptr<const LoopKeyframe> keyframe);
  size_t size() const { return keyframes_.size(); }
  // nullptr when no keyframe has this id.
  std::shared_ptr<const LoopKeyframe> Find(int id) const;
  const std::vector<std::shared_ptr<const LoopKeyframe>>& keyframes() const { return keyframes_; }

  struct Match {
    int id = 0;
    double score = 0;  // histogram intersection with the query's words, 0-1
  };
  // The best `max_results` keyframes for which allowed(id) holds, best first (score > 0 only;
  // none before the vocabulary exists).
  std::vector<Match> QueryAppearance(const cv::Mat& descriptors, int max_results,
                                     const std::function<bool(int)>& allowed) const;
  bool has_vocabulary() const { return !vocabulary_.empty(); }
  // Bytes held by the keyframes and the index, for the memory figures.
  size_t MemoryBytes() const;

 private:
  using WordHistogram = std::vector<std::pair<int, float>>;  // (word, weight), sorted by word
  void TrainVocabulary();
  WordHistogram Describe(const cv::Mat& descriptors) const;
  void Index(size_t position);
  KeyframeDatabaseOptions options_;
  std::vector<std::shared_ptr<const LoopKeyframe>> keyframes_;
  cv::Mat vocabulary_;       // CV_32F, a word per row
  std::vector<float> idf_;   // per word
  std::vector<std::vector<std::pair<int, float>>> inverted_;  // word -> (position, weight)
  size_t described_ = 0;     // keyframes_[0, described_) are in the inverted index
};

}  // namespace gf
