#include "registration/icp.h"

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <cstdio>
#include <opencv2/core/utility.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

double HuberWeight(double normalized_residual, double threshold) {
  const double a = std::abs(normalized_residual);
  return a <= threshold ? 1.0 : threshold / a;
}

// Normal equations of the point-to-plane term over a band of rows.
struct DenseAccumulator {
  Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();  // upper triangle
  Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
  int inliers = 0, valid = 0, overlapping = 0;
  double sum2 = 0;
  DenseAccumulator& operator+=(const DenseAccumulator& o) {
    h += o.h;
    g += o.g;
    inliers += o.inliers;
    overlapping += o.overlapping;
    valid += o.valid;
    sum2 += o.sum2;
    return *this;
  }
};

struct DenseLevel {
  const Camera& cam;
  const cv::Mat& ref_v;
  const cv::Mat& ref_n;
  const cv::Mat& cur_v;
  const cv::Mat& cur_n;
  const SE3& t;
  double cos_max_angle, plane_scale, sigma_at_1m;
  const IcpOptions* options;
};

// h_upper (the upper triangle of a 6x6 matrix, row by row: 21 entries) += w j j^T and
// g += w residual j, rounded as Eigen's rankUpdate and `g += w * residual * j` round them (entry
// (row, col) gets (w j_col) j_row), so the poses are the same to the bit. Written out so that it
// compiles to 27 multiply-adds per point: rankUpdate is a call into a generic product per point.
inline void AddWeightedOuter(const double (&j)[6], double w, double residual, double* h_upper,
                             double* g) {
  const double wr = w * residual;
  const double wj[6] = {w * j[0], w * j[1], w * j[2], w * j[3], w * j[4], w * j[5]};
  int k = 0;
#pragma GCC unroll 6
  for (int row = 0; row < 6; ++row) {
#pragma GCC unroll 6
    for (int col = row; col < 6; ++col) h_upper[k++] += wj[col] * j[row];
    g[row] += wr * j[row];
  }
}

DenseAccumulator AccumulateDense(const DenseLevel& l, int row_begin, int row_end) {
  const IcpOptions& options = *l.options;
  DenseAccumulator a;
  const Eigen::Matrix3f r = l.t.RotationMatrix().cast<float>();
  const Eigen::Vector3f tr = l.t.translation().cast<float>();
  const float max_d2 = static_cast<float>(options.max_distance_m * options.max_distance_m);
  double h_upper[21] = {}, g[6] = {};
  for (int y = row_begin; y < row_end; ++y) {
    const cv::Vec3f* vrow = l.cur_v.ptr<cv::Vec3f>(y);
    const cv::Vec3f* nrow = l.cur_n.ptr<cv::Vec3f>(y);
    for (int x = 0; x < l.cur_v.cols; ++x) {
      const cv::Vec3f& pv = vrow[x];
      const cv::Vec3f& pn = nrow[x];
      if (std::isnan(pn[0])) continue;
      ++a.valid;
      const Eigen::Vector3f p = r * Eigen::Vector3f(pv[0], pv[1], pv[2]) + tr;
      if (p.z() <= 0) continue;
      // The nearest pixel, tested in float before the conversion (which a point far outside
      // would overflow); truncating x + 0.5 rounds it there (std::lround is a library call per
      // point on baseline x86-64).
      const float uf = static_cast<float>(l.cam.fx * p.x() / p.z() + l.cam.cx);
      const float vf = static_cast<float>(l.cam.fy * p.y() / p.z() + l.cam.cy);
      if (!(uf >= -0.5f && vf >= -0.5f && uf < l.ref_v.cols - 0.5f && vf < l.ref_v.rows - 0.5f))
        continue;
      const int u = static_cast<int>(uf + 0.5f), v = static_cast<int>(vf + 0.5f);
      const cv::Vec3f& qn = l.ref_n.at<cv::Vec3f>(v, u);
      if (std::isnan(qn[0])) continue;
      ++a.overlapping;
      const cv::Vec3f& qv = l.ref_v.at<cv::Vec3f>(v, u);
      const Eigen::Vector3f q(qv[0], qv[1], qv[2]);
      const Eigen::Vector3f n(qn[0], qn[1], qn[2]);
      if ((p - q).squaredNorm() > max_d2) continue;
      const Eigen::Vector3f n_cur = r * Eigen::Vector3f(pn[0], pn[1], pn[2]);
      if (n.dot(n_cur) < l.cos_max_angle) continue;
      const double residual = n.dot(p - q);
      ++a.inliers;
      a.sum2 += residual * residual;
      double scale = l.plane_scale;
      if (options.depth_weighting) {
        const double dz = q.z() - 0.4;
        scale *= l.sigma_at_1m / (options.noise_a_m + options.noise_b_per_m * dz * dz);
      }
      const double w = HuberWeight(residual * scale, options.plane_huber) * scale * scale;
      const Eigen::Vector3d c = p.cast<double>().cross(n.cast<double>());
      const double j[6] = {n.x(), n.y(), n.z(), c.x(), c.y(), c.z()};
      AddWeightedOuter(j, w, residual, h_upper, g);
    }
  }
  for (int i = 0, k = 0; i < 6; ++i) {
    for (int col = i; col < 6; ++col) a.h(i, col) = h_upper[k++];
    a.g(i) = g[i];
  }
  return a;
}

}  // namespace

bool IcpOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Each("iterations", iterations, 0, kMaxIterations, kMoreIterationsThanAFrameAllows)
      .Above("max_distance_m", max_distance_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("max_normal_angle_deg", max_normal_angle_deg, 0, kMaxAngleDeg, kMoreThanAHalfTurn)
      .Above("plane_sigma_m", plane_sigma_m, 0, kMaxDepthM, kFartherThanAnySensor)
      // The noise model's sigma(z) = a + b (z - 0.4)^2: a sensor whose noise reaches the whole
      // range of depths measures nothing.
      .Above("noise_a_m", noise_a_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .In("noise_b_per_m", noise_b_per_m, 0, kMaxDepthM, kFartherThanAnySensor)
      .Above("plane_huber", plane_huber, 0, kMaxSigmas, kMoreSigmasThanMeasurable)
      .Above("feature_sigma_px", feature_sigma_px, 0, kMaxImageSidePx, kLargerThanAnyImage)
      .Above("feature_huber", feature_huber, 0, kMaxSigmas, kMoreSigmasThanMeasurable)
      .In("feature_weight", feature_weight, 0, kMaxRelativeWeight, kOutweighsBeyondRounding)
      // Levels of a pyramid that halves an image of at most 4096 pixels down to one pixel.
      .In("feature_min_level", feature_min_level, 0, kMaxPyramidLevels, kMoreLevelsThanAnyPyramid)
      .In("min_inliers", min_inliers, 0, kMaxImagePixels, kMoreThanAnImagesPixels)
      .Above("max_rmse_m", max_rmse_m, 0, kMaxDepthM, kFartherThanAnySensor)
      // A step of a metre or a radian (57 degrees) per iteration is no convergence.
      .Above("convergence_step", convergence_step, 0, 1,
             "is a step of more than a metre or a "
             "radian, no convergence");
  return c.ok();
}

std::string IcpSummary::BriefReport() const {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer),
                "ICP %s (%s): %d iterations, %d/%d inliers, rmse %.4f m, %d feature inliers",
                success ? "ok" : "failed", termination.c_str(), iterations, inliers, valid_points,
                rmse_m, feature_inliers);
  return buffer;
}

double PointToPlaneResidual(const SE3& t, const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& n, Eigen::Matrix<double, 1, 6>* jacobian) {
  const Eigen::Vector3d x = t * p;
  if (jacobian) {
    jacobian->head<3>() = n.transpose();
    jacobian->tail<3>() = x.cross(n).transpose();
  }
  return n.dot(x - q);
}

Eigen::Vector2d ReprojectionResidual(const SE3& t, const Camera& camera, const Eigen::Vector3d& p,
                                     const Eigen::Vector2d& u,
                                     Eigen::Matrix<double, 2, 6>* jacobian) {
  const Eigen::Vector3d x = t * p;
  const double iz = 1.0 / x.z();
  if (jacobian) {
    Eigen::Matrix<double, 2, 3> d_proj;
    d_proj << camera.fx * iz, 0, -camera.fx * x.x() * iz * iz, 0, camera.fy * iz,
        -camera.fy * x.y() * iz * iz;
    Eigen::Matrix<double, 3, 6> d_point;
    d_point.leftCols<3>() = Eigen::Matrix3d::Identity();
    d_point.rightCols<3>() = -Hat(x);
    *jacobian = d_proj * d_point;
  }
  return Eigen::Vector2d(camera.fx * x.x() * iz + camera.cx - u.x(),
                         camera.fy * x.y() * iz + camera.cy - u.y());
}

namespace {

// The dense term: fixed horizontal stripes accumulated in parallel, summed in stripe order, so
// the result does not depend on thread scheduling.
DenseAccumulator AccumulateDenseStripes(const DenseLevel& level) {
  constexpr int kStripes = 16;
  const int rows = level.cur_v.rows;
  std::array<DenseAccumulator, kStripes> parts;
  cv::parallel_for_(cv::Range(0, kStripes), [&](const cv::Range& range) {
    for (int stripe = range.start; stripe < range.end; ++stripe)
      parts[stripe] =
          AccumulateDense(level, rows * stripe / kStripes, rows * (stripe + 1) / kStripes);
  });
  DenseAccumulator dense;
  for (const DenseAccumulator& part : parts) dense += part;
  return dense;
}

// The features' reprojection term at pyramid `level` (pixels observed at level 0), Huber-weighted,
// added to the upper triangle of h and to g. Returns the features within the Huber threshold.
int AddFeatureTerm(const std::vector<FeatureCorrespondence>& features, const SE3& t,
                   const Camera& cam, int level, const IcpOptions& options,
                   Eigen::Matrix<double, 6, 6>* h, Eigen::Matrix<double, 6, 1>* g) {
  const double feature_scale = 1.0 / options.feature_sigma_px;
  int feature_inliers = 0;
  for (const FeatureCorrespondence& f : features) {
    if ((t * f.point_in_current).z() <= 0) continue;
    Eigen::Matrix<double, 2, 6> j;
    // Features are observed at level 0: scale pixels to this level.
    const double s = std::ldexp(1.0, -level);
    const Eigen::Vector2d pixel = (f.pixel_in_reference.array() + 0.5) * s - 0.5;
    const Eigen::Vector2d residual = ReprojectionResidual(t, cam, f.point_in_current, pixel, &j);
    const double norm = residual.norm() * feature_scale / s;
    feature_inliers += norm <= options.feature_huber;
    const double w = options.feature_weight * HuberWeight(norm, options.feature_huber) *
                     feature_scale * feature_scale / (s * s);
    h->selfadjointView<Eigen::Upper>().rankUpdate(j.transpose(), w);
    *g += w * j.transpose() * residual;
  }
  return feature_inliers;
}

}  // namespace

IcpSummary AlignPointToPlane(const DepthPyramid& reference, const DepthPyramid& current,
                             const SE3& initial, const IcpOptions& options,
                             const std::vector<FeatureCorrespondence>& features) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(reference.levels() >= static_cast<int>(options.iterations.size()) &&
               current.levels() >= static_cast<int>(options.iterations.size()),
           "pyramids have fewer levels than options.iterations");
  IcpSummary summary;
  SE3 t = initial;
  const double cos_max_angle = std::cos(options.max_normal_angle_deg * M_PI / 180.0);
  const double plane_scale = 1.0 / options.plane_sigma_m;
  const double sigma_at_1m = options.noise_a_m + options.noise_b_per_m * 0.36;
  const int n_levels = static_cast<int>(options.iterations.size());
  bool converged_at_finest = false;

  for (int li = 0; li < n_levels; ++li) {
    const int level = n_levels - 1 - li;  // coarsest first
    const Camera& cam = reference.cameras[level];
    const cv::Mat& ref_v = reference.vertices[level];
    const cv::Mat& ref_n = reference.normals[level];
    const cv::Mat& cur_v = current.vertices[level];
    const cv::Mat& cur_n = current.normals[level];
    const bool finest = level == 0;
    // The extra pass after the last step only measures (inliers, RMSE, information), which only
    // the finest level reports.
    const int passes = options.iterations[li] + (finest ? 1 : 0);
    for (int it = 0; it < passes; ++it) {
      const bool measure_only = it == options.iterations[li];
      const DenseAccumulator dense = AccumulateDenseStripes(
          {cam, ref_v, ref_n, cur_v, cur_n, t, cos_max_angle, plane_scale, sigma_at_1m, &options});
      Eigen::Matrix<double, 6, 6> h = dense.h;
      Eigen::Matrix<double, 6, 1> g = dense.g;
      const int inliers = dense.inliers, valid = dense.valid;
      const double sum2 = dense.sum2;
      int feature_inliers = 0;
      if (options.feature_weight > 0 && level >= options.feature_min_level)
        feature_inliers = AddFeatureTerm(features, t, cam, level, options, &h, &g);
      h = h.selfadjointView<Eigen::Upper>();
      if (finest) {
        summary.inliers = inliers;
        summary.valid_points = valid;
        summary.overlapping_points = dense.overlapping;
        summary.rmse_m = inliers ? std::sqrt(sum2 / inliers) : 0.0;
        summary.feature_inliers = feature_inliers;
        summary.information = h;
      }
      if (measure_only) break;
      if (inliers < 6) break;  // nothing to solve with at this level
      const Eigen::Matrix<double, 6, 1> xi = h.ldlt().solve(-g);
      if (!xi.allFinite()) break;
      t = SE3::Exp(xi) * t;
      ++summary.iterations;
      if (xi.head<3>().norm() < options.convergence_step &&
          xi.tail<3>().norm() < options.convergence_step) {
        if (finest) converged_at_finest = true;
        // Measure at the converged pose (finest level) or leave the level.
        if (!finest) break;
        it = options.iterations[li] - 1;
      }
    }
  }
  summary.reference_from_current = t;
  if (summary.inliers < options.min_inliers) {
    summary.termination = "too few inliers (" + std::to_string(summary.inliers) + ")";
  } else if (summary.rmse_m > options.max_rmse_m) {
    summary.termination = "residual too large";
  } else {
    summary.success = true;
    summary.termination = converged_at_finest ? "converged" : "max iterations";
  }
  return summary;
}

}  // namespace gf
