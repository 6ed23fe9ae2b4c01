#include "registration/keyframe_database.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {

std::shared_ptr<const LoopKeyframe> MakeLoopKeyframe(int id, const RgbdFrame& frame,
                                                     const SE3& world_from_camera,
                                                     std::shared_ptr<const FrameFeatures> features) {
  GF_CHECK(frame.depth.type() == CV_32FC1, "loop keyframes need metric depth");
  auto k = std::make_shared<LoopKeyframe>();
  k->id = id;
  k->name = KeyframeName(frame);
  k->world_from_camera = world_from_camera;
  k->features = features ? std::move(features) : std::make_shared<const FrameFeatures>();
  cv::Mat half;
  cv::resize(frame.depth, half, {frame.depth.cols / 2, frame.depth.rows / 2}, 0, 0,
             cv::INTER_NEAREST);
  half.convertTo(k->depth, CV_16U, 1000.0);  // saturates: beyond 65 m reads 65 m
  std::vector<float> measured;
  for (int y = 0; y < half.rows; y += 4)
    for (int x = 0; x < half.cols; x += 4)
      if (half.at<float>(y, x) > 0) measured.push_back(half.at<float>(y, x));
  if (!measured.empty()) {
    std::nth_element(measured.begin(), measured.begin() + measured.size() / 2, measured.end());
    k->median_depth_m = measured[measured.size() / 2];
  }
  return k;
}

bool KeyframeDatabaseOptions::Check(std::string* message) const {
  // A word is a descriptor's centre (64 floats, 256 bytes): no more words than a keyframe has
  // pixels (4 GiB of centres at that bound).
  FieldCheck c(message);
  c.In("words", words, 2, kMaxImagePixels, kMoreThanAnImagesPixels)
      .In("vocabulary_keyframes", vocabulary_keyframes, 1, kMaxCaptureFrames,
          kMoreFramesThanACapture)
      .In("kmeans_iterations", kmeans_iterations, 1, kMaxIterations,
          kMoreIterationsThanAFrameAllows);
  return c.ok();
}

KeyframeDatabase::KeyframeDatabase(const KeyframeDatabaseOptions& options) : options_(options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
}

KeyframeDatabase::~KeyframeDatabase() = default;

void KeyframeDatabase::Add(std::shared_ptr<const LoopKeyframe> keyframe) {
  GF_CHECK(keyframe != nullptr && keyframe->features != nullptr, "a keyframe with features");
  GF_CHECK(keyframes_.empty() || keyframe->id > keyframes_.back()->id,
           "keyframes enter the database in increasing id order");
  keyframes_.push_back(std::move(keyframe));
  if (!has_vocabulary() &&
      keyframes_.size() >= static_cast<size_t>(options_.vocabulary_keyframes))
    TrainVocabulary();
  if (has_vocabulary())
    while (described_ < keyframes_.size()) Index(described_++);
}

std::shared_ptr<const LoopKeyframe> KeyframeDatabase::Find(int id) const {
  const auto it = std::lower_bound(
      keyframes_.begin(), keyframes_.end(), id,
      [](const std::shared_ptr<const LoopKeyframe>& k, int value) { return k->id < value; });
  return it != keyframes_.end() && (*it)->id == id ? *it : nullptr;
}

void KeyframeDatabase::TrainVocabulary() {
  std::vector<cv::Mat> rows;
  for (const auto& k : keyframes_)
    if (!k->features->descriptors.empty()) rows.push_back(k->features->descriptors);
  if (rows.empty()) return;
  cv::Mat samples;
  cv::vconcat(rows, samples);
  // At least ten descriptors a word, or the clusters are single descriptors.
  const int words = std::min(options_.words, samples.rows / 10);
  if (words < 2) return;
  cv::Mat labels;
  cv::setRNGSeed(1);  // the same vocabulary for the same capture
  cv::kmeans(samples, words, labels,
             cv::TermCriteria(cv::TermCriteria::MAX_ITER, options_.kmeans_iterations, 0), 1,
             cv::KMEANS_PP_CENTERS, vocabulary_);
  // idf: log(keyframes / keyframes containing the word), over the training keyframes.
  std::vector<int> containing(words, 0);
  int described = 0;
  for (const auto& k : keyframes_) {
    if (k->features->descriptors.empty()) continue;
    ++described;
    std::vector<uint8_t> seen(words, 0);
    cv::Mat nearest, distance;
    cv::batchDistance(k->features->descriptors, vocabulary_, distance, CV_32F, nearest,
                      cv::NORM_L2SQR, 1);
    for (int r = 0; r < nearest.rows; ++r) seen[nearest.at<int>(r)] = 1;
    for (int w = 0; w < words; ++w) containing[w] += seen[w];
  }
  idf_.resize(words);
  for (int w = 0; w < words; ++w)
    idf_[w] = static_cast<float>(std::log((described + 1.0) / (containing[w] + 1.0)) + 1e-3);
  inverted_.assign(words, {});
}

KeyframeDatabase::WordHistogram KeyframeDatabase::Describe(const cv::Mat& descriptors) const {
  WordHistogram h;
  if (descriptors.empty() || vocabulary_.empty()) return h;
  cv::Mat nearest, distance;
  cv::batchDistance(descriptors, vocabulary_, distance, CV_32F, nearest, cv::NORM_L2SQR, 1);
  std::vector<float> weight(vocabulary_.rows, 0.f);
  for (int r = 0; r < nearest.rows; ++r) weight[nearest.at<int>(r)] += idf_[nearest.at<int>(r)];
  double sum = 0;
  for (float w : weight) sum += w;
  if (!(sum > 0)) return h;
  for (int w = 0; w < vocabulary_.rows; ++w)
    if (weight[w] > 0) h.emplace_back(w, static_cast<float>(weight[w] / sum));
  return h;
}

void KeyframeDatabase::Index(size_t position) {
  for (const auto& [word, weight] : Describe(keyframes_[position]->features->descriptors))
    inverted_[word].emplace_back(static_cast<int>(position), weight);
}

std::vector<KeyframeDatabase::Match> KeyframeDatabase::QueryAppearance(
    const cv::Mat& descriptors, int max_results, const std::function<bool(int)>& allowed) const {
  std::vector<double> score(keyframes_.size(), 0.0);
  // Histogram intersection: the sum over shared words of the smaller weight.
  for (const auto& [word, weight] : Describe(descriptors))
    for (const auto& [position, other] : inverted_[word]) score[position] += std::min(weight, other);
  std::vector<Match> matches;
  for (size_t i = 0; i < keyframes_.size(); ++i)
    if (score[i] > 0 && allowed(keyframes_[i]->id)) matches.push_back({keyframes_[i]->id, score[i]});
  std::sort(matches.begin(), matches.end(),
            [](const Match& a, const Match& b) { return a.score > b.score; });
  if (static_cast<int>(matches.size()) > max_results) matches.resize(max_results);
  return matches;
}

size_t KeyframeDatabase::MemoryBytes() const {
  size_t bytes = vocabulary_.total() * vocabulary_.elemSize();
  for (const auto& postings : inverted_) bytes += postings.capacity() * sizeof(postings[0]);
  for (const auto& k : keyframes_) {
    bytes += sizeof(LoopKeyframe) + k->depth.total() * k->depth.elemSize();
    const FrameFeatures& f = *k->features;
    bytes += f.descriptors.total() * f.descriptors.elemSize() +
             f.keypoints.capacity() * sizeof(cv::KeyPoint) +
             f.points.capacity() * sizeof(Eigen::Vector3d);
  }
  return bytes;
}

}  // namespace gf
