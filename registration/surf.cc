#include "registration/surf.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"

namespace gf {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Sums over axis-aligned boxes from an integral image (CV_32S, (h+1) x (w+1)), clipped to the
// image.
class Integral {
 public:
  explicit Integral(const cv::Mat& gray) {
    cv::integral(gray, sum_, CV_32S);
    rows_ = gray.rows;
    cols_ = gray.cols;
    data_ = sum_.ptr<int>(0);
    stride_ = static_cast<int>(sum_.step1());
  }
  // Sum of pixels in rows [row, row + height), cols [col, col + width), clipped; in [0, 255] units.
  double Box(int row, int col, int height, int width) const {
    if (row >= 0 && col >= 0 && row + height <= rows_ && col + width <= cols_) {
      const int* a = data_ + row * stride_;
      const int* b = a + height * stride_;
      return static_cast<double>(b[col + width] - b[col] - a[col + width] + a[col]);
    }
    const int r0 = std::clamp(row, 0, rows_), c0 = std::clamp(col, 0, cols_);
    const int r1 = std::clamp(row + height, 0, rows_), c1 = std::clamp(col + width, 0, cols_);
    if (r1 <= r0 || c1 <= c0) return 0.0;
    const int* a = data_ + r0 * stride_;
    const int* b = data_ + r1 * stride_;
    return static_cast<double>(b[c1] - b[c0] - a[c1] + a[c0]);
  }
  // Haar wavelet responses of side `size` centred at (row, col): right minus left, bottom minus
  // top.
  double HaarX(int row, int col, int size) const {
    const int h = size / 2;
    return Box(row - h, col, size, h) - Box(row - h, col - h, size, h);
  }
  double HaarY(int row, int col, int size) const {
    const int h = size / 2;
    return Box(row, col - h, h, size) - Box(row - h, col - h, h, size);
  }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  const int* data() const { return data_; }
  int stride() const { return stride_; }

 private:
  cv::Mat sum_;
  const int* data_ = nullptr;
  int stride_ = 0;
  int rows_ = 0, cols_ = 0;
};

// det(H) and Laplacian sign of one scale level, sampled every `step` pixels.
struct ResponseLayer {
  int filter = 0;  // filter side L, pixels
  int step = 1;
  int rows = 0, cols = 0;
  std::vector<float> det;
  std::vector<int8_t> laplacian;
  float At(int r, int c) const { return det[r * cols + c]; }
};

ResponseLayer ComputeLayer(const Integral& ii, int filter, int step) {
  ResponseLayer layer;
  layer.filter = filter;
  layer.step = step;
  layer.rows = ii.rows() / step;
  layer.cols = ii.cols() / step;
  layer.det.assign(static_cast<size_t>(layer.rows) * layer.cols, 0.f);
  layer.laplacian.assign(layer.det.size(), 1);
  const int lobe = filter / 3;
  const int border = (filter - 1) / 2;
  // Normalise by the filter area, and to an image in [0, 1] (the integral holds 0..255).
  const double norm = 1.0 / (static_cast<double>(filter) * filter * 255.0);
  // The eight boxes, as (row offset, col offset, height, width) from the sample.
  const int boxes[8][4] = {{-border, -lobe + 1, filter, 2 * lobe - 1},  // Dyy outer
                           {-lobe / 2, -lobe + 1, lobe, 2 * lobe - 1},  // Dyy middle lobe
                           {-lobe + 1, -border, 2 * lobe - 1, filter},  // Dxx outer
                           {-lobe + 1, -lobe / 2, 2 * lobe - 1, lobe},  // Dxx middle lobe
                           {-lobe, 1, lobe, lobe},
                           {1, -lobe, lobe, lobe},  // Dxy +
                           {-lobe, -lobe, lobe, lobe},
                           {1, 1, lobe, lobe}};  // Dxy -
  // Away from the border every box lies inside the image: four reads per box at fixed offsets.
  const int stride = ii.stride();
  int corner[8][4];
  for (int b = 0; b < 8; ++b) {
    const int tl = boxes[b][0] * stride + boxes[b][1];
    corner[b][0] = tl;
    corner[b][1] = tl + boxes[b][3];
    corner[b][2] = tl + boxes[b][2] * stride;
    corner[b][3] = corner[b][2] + boxes[b][3];
  }
  auto box = [&](int r, int c, int b) {
    if (r >= border && c >= border && r + border + 1 <= ii.rows() && c + border + 1 <= ii.cols()) {
      const int* p = ii.data() + r * stride + c;
      return static_cast<double>(p[corner[b][3]] - p[corner[b][2]] - p[corner[b][1]] +
                                 p[corner[b][0]]);
    }
    return ii.Box(r + boxes[b][0], c + boxes[b][1], boxes[b][2], boxes[b][3]);
  };
  for (int ar = 0; ar < layer.rows; ++ar) {
    const int r = ar * step;
    for (int ac = 0; ac < layer.cols; ++ac) {
      const int c = ac * step;
      // Dyy: three lobes stacked vertically, each lobe x (2 lobe - 1), the middle weighted -2.
      const double dyy = box(r, c, 0) - 3.0 * box(r, c, 1);
      const double dxx = box(r, c, 2) - 3.0 * box(r, c, 3);
      const double dxy = box(r, c, 4) + box(r, c, 5) - box(r, c, 6) - box(r, c, 7);
      const double xx = dxx * norm, yy = dyy * norm, xy = dxy * norm;
      const size_t i = static_cast<size_t>(ar) * layer.cols + ac;
      layer.det[i] = static_cast<float>(xx * yy - 0.81 * xy * xy);
      layer.laplacian[i] = xx + yy >= 0 ? 1 : -1;
    }
  }
  return layer;
}

struct Candidate {
  double x, y, scale, response;
  int laplacian;
};

// Is (r, c) of layer m a maximum over its 3x3x3 neighbourhood in (b, m, t)? Then refine it.
bool RefineExtremum(const ResponseLayer& b, const ResponseLayer& m, const ResponseLayer& t, int r,
                    int c, double threshold, Candidate* out) {
  const float v = m.At(r, c);
  if (v < threshold) return false;
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc) {
      if (t.At(r + dr, c + dc) >= v || b.At(r + dr, c + dc) >= v) return false;
      if ((dr || dc) && m.At(r + dr, c + dc) >= v) return false;
    }
  // Quadratic fit in (x, y, s): offset = -H^-1 g from finite differences.
  const double dx = (m.At(r, c + 1) - m.At(r, c - 1)) / 2.0;
  const double dy = (m.At(r + 1, c) - m.At(r - 1, c)) / 2.0;
  const double ds = (t.At(r, c) - b.At(r, c)) / 2.0;
  const double dxx = m.At(r, c + 1) + m.At(r, c - 1) - 2.0 * v;
  const double dyy = m.At(r + 1, c) + m.At(r - 1, c) - 2.0 * v;
  const double dss = t.At(r, c) + b.At(r, c) - 2.0 * v;
  const double dxy =
      (m.At(r + 1, c + 1) - m.At(r + 1, c - 1) - m.At(r - 1, c + 1) + m.At(r - 1, c - 1)) / 4.0;
  const double dxs = (t.At(r, c + 1) - t.At(r, c - 1) - b.At(r, c + 1) + b.At(r, c - 1)) / 4.0;
  const double dys = (t.At(r + 1, c) - t.At(r - 1, c) - b.At(r + 1, c) + b.At(r - 1, c)) / 4.0;
  Eigen::Matrix3d h;
  h << dxx, dxy, dxs, dxy, dyy, dys, dxs, dys, dss;
  const Eigen::Vector3d offset = -h.colPivHouseholderQr().solve(Eigen::Vector3d(dx, dy, ds));
  if (!offset.allFinite() || offset.cwiseAbs().maxCoeff() >= 0.5) return false;
  const int filter_step = (m.filter - b.filter);
  out->x = (c + offset.x()) * m.step;
  out->y = (r + offset.y()) * m.step;
  out->scale = 1.2 / 9.0 * (m.filter + offset.z() * filter_step);
  out->response = v;
  out->laplacian = m.laplacian[static_cast<size_t>(r) * m.cols + c];
  return true;
}

inline int RoundToInt(double v) { return static_cast<int>(std::floor(v + 0.5)); }

double Gaussian(double x, double y, double sigma) {
  return std::exp(-(x * x + y * y) / (2.0 * sigma * sigma));
}

// Gaussian weights on the sample grids, computed once.
struct GaussianTables {
  double orientation[13][13];  // sigma 2 (units of s), offsets -6..6
  double descriptor[20][20];   // sigma 3.3, sample centres -9.5..9.5
  GaussianTables() {
    for (int i = 0; i < 13; ++i)
      for (int j = 0; j < 13; ++j) orientation[i][j] = Gaussian(i - 6, j - 6, 2.0);
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j) descriptor[i][j] = Gaussian(i - 9.5, j - 9.5, 3.3);
  }
};
const GaussianTables& Tables() {
  static const GaussianTables tables;
  return tables;
}

double Orientation(const Integral& ii, const Candidate& k) {
  const int s = std::max(1, RoundToInt((k.scale)));
  const int r0 = RoundToInt((k.y)), c0 = RoundToInt((k.x));
  std::vector<double> rx, ry, angle;
  for (int i = -6; i <= 6; ++i) {
    for (int j = -6; j <= 6; ++j) {
      if (i * i + j * j >= 36) continue;
      const double w = Tables().orientation[i + 6][j + 6];  // sigma 2s
      const double hx = w * ii.HaarX(r0 + j * s, c0 + i * s, 4 * s);
      const double hy = w * ii.HaarY(r0 + j * s, c0 + i * s, 4 * s);
      rx.push_back(hx);
      ry.push_back(hy);
      angle.push_back(std::atan2(hy, hx));
    }
  }
  // Sliding pi/3 window over the responses sorted by angle: prefix sums over the samples, listed
  // twice (second time shifted by 2 pi) so windows that wrap around are contiguous.
  std::vector<int> order(angle.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return angle[x] < angle[y]; });
  const size_t n = order.size();
  std::vector<double> sorted_angle(2 * n), prefix_x(2 * n + 1, 0.0), prefix_y(2 * n + 1, 0.0);
  for (size_t i = 0; i < 2 * n; ++i) {
    const int o = order[i % n];
    sorted_angle[i] = angle[o] + (i >= n ? 2 * kPi : 0.0);
    prefix_x[i + 1] = prefix_x[i] + rx[o];
    prefix_y[i + 1] = prefix_y[i] + ry[o];
  }
  double best = -1, best_angle = 0;
  for (double a = -kPi; a < kPi; a += 0.15) {
    const size_t lo =
        std::lower_bound(sorted_angle.begin(), sorted_angle.end(), a) - sorted_angle.begin();
    const size_t hi = std::lower_bound(sorted_angle.begin(), sorted_angle.end(), a + kPi / 3) -
                      sorted_angle.begin();
    const double sx = prefix_x[hi] - prefix_x[lo], sy = prefix_y[hi] - prefix_y[lo];
    if (sx * sx + sy * sy > best) {
      best = sx * sx + sy * sy;
      best_angle = std::atan2(sy, sx);
    }
  }
  return best_angle;
}

void Describe(const Integral& ii, const Candidate& k, double angle, float* descriptor) {
  const double s = k.scale;
  const int haar = std::max(2, 2 * RoundToInt((s)));
  const double co = std::cos(angle), si = std::sin(angle);
  int index = 0;
  double norm2 = 0;
  for (int i = -2; i < 2; ++i) {    // subregion columns (along the orientation)
    for (int j = -2; j < 2; ++j) {  // subregion rows
      double sdx = 0, sdy = 0, adx = 0, ady = 0;
      for (int u = 0; u < 5; ++u) {
        for (int v = 0; v < 5; ++v) {
          // Sample in the keypoint frame, in units of s, centred on the sample cell.
          const double lx = (i * 5 + u + 0.5), ly = (j * 5 + v + 0.5);
          const double px = k.x + s * (co * lx - si * ly);
          const double py = k.y + s * (si * lx + co * ly);
          const int r = RoundToInt((py)), c = RoundToInt((px));
          const double w = Tables().descriptor[i * 5 + u + 10][j * 5 + v + 10];  // sigma 3.3s
          const double hx = ii.HaarX(r, c, haar), hy = ii.HaarY(r, c, haar);
          // Rotate the responses into the keypoint frame.
          const double rdx = w * (co * hx + si * hy);
          const double rdy = w * (-si * hx + co * hy);
          sdx += rdx;
          sdy += rdy;
          adx += std::abs(rdx);
          ady += std::abs(rdy);
        }
      }
      for (double value : {sdx, sdy, adx, ady}) {
        descriptor[index++] = static_cast<float>(value);
        norm2 += value * value;
      }
    }
  }
  const double inv = norm2 > 0 ? 1.0 / std::sqrt(norm2) : 0.0;
  for (int i = 0; i < 64; ++i) descriptor[i] = static_cast<float>(descriptor[i] * inv);
}

}  // namespace

bool SurfOptions::Check(std::string* message) const {
  // Box-filter second derivatives of an image in [0, 1], normalised by the filter's area, are at
  // most 2/3 (Dxy 2/9), so det(H) stays below 1: a larger threshold keeps no feature.
  FieldCheck c(message);
  c.In("hessian_threshold", hessian_threshold, 0, 1, "is more than det(H) of any image reaches")
      .In("octaves", octaves, 1, 6, "is more octaves than SURF's filters fit in an image")
      .In("initial_step", initial_step, 1, 4, "is coarser than SURF's first octave samples")
      .In("max_features", max_features, 0, kMaxImagePixels, kMoreThanAnImagesPixels);
  return c.ok();
}

SurfFeatures DetectAndDescribeSurf(const cv::Mat& gray, const SurfOptions& options) {
  std::string problem;
  GF_CHECK(options.Check(&problem), problem);
  GF_CHECK(gray.type() == CV_8UC1, "SURF needs an 8-bit grey image");
  const Integral ii(gray);

  // Scale space: octave o has filters 3 * (2^(o+1) * (i+1) + 1), i = 0..3, step initial * 2^o.
  std::vector<Candidate> candidates;
  for (int o = 0; o < options.octaves; ++o) {
    const int step = options.initial_step << o;
    std::vector<ResponseLayer> layers;
    for (int i = 0; i < 4; ++i) {
      const int filter = 3 * ((2 << o) * (i + 1) + 1);
      if (filter > std::min(gray.rows, gray.cols)) break;
      layers.push_back(ComputeLayer(ii, filter, step));
    }
    for (size_t m = 1; m + 1 < layers.size(); ++m) {
      const ResponseLayer &b = layers[m - 1], &mid = layers[m], &t = layers[m + 1];
      // Stay clear of the border the largest filter of the triple cannot see.
      const int margin = (t.filter / 2) / step + 1;
      for (int r = margin; r < mid.rows - margin; ++r)
        for (int c = margin; c < mid.cols - margin; ++c) {
          Candidate k;
          if (RefineExtremum(b, mid, t, r, c, options.hessian_threshold, &k))
            candidates.push_back(k);
        }
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.response > b.response; });
  if (options.max_features > 0 && static_cast<int>(candidates.size()) > options.max_features)
    candidates.resize(options.max_features);

  SurfFeatures f;
  f.descriptors.create(static_cast<int>(candidates.size()), 64, CV_32F);
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Candidate& k = candidates[i];
    const double angle = options.upright ? 0.0 : Orientation(ii, k);
    Describe(ii, k, angle, f.descriptors.ptr<float>(static_cast<int>(i)));
    double degrees = angle * 180.0 / kPi;
    if (degrees < 0) degrees += 360.0;
    f.keypoints.emplace_back(cv::Point2f(static_cast<float>(k.x), static_cast<float>(k.y)),
                             static_cast<float>(20.0 * k.scale),
                             options.upright ? -1.f : static_cast<float>(degrees),
                             static_cast<float>(k.response), 0, k.laplacian);
  }
  return f;
}

}  // namespace gf
