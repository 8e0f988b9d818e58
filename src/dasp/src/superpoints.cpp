// The superpoint fit (thesis §3.2.3).
#include "dasp/superpoints.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "dasp/density.h"
#include "run_sums.h"
#include "simd.h"

namespace dasp {
namespace {
constexpr double kPiD = 3.14159265358979323846;

struct FitTotals {
  double n = 0, u = 0, v = 0, density = 0;
  Eigen::Vector3d color = Eigen::Vector3d::Zero();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // first point, for precision
};

// Runs of equal labels are summed in float registers (relative to the label's first point),
// then added to the double totals. Returns the largest label seen.
template <bool kDepth, bool kRho>
DASP_ALWAYS_INLINE int accumulateFit(const cv::Mat& labels, const PixelFeatures& features,
                                     const float* rho, std::vector<FitTotals>& sums) {
  const int width = labels.cols;
  int max_label = -1;
  for (int row = 0; row < labels.rows; ++row) {
    const int* l = labels.ptr<int>(row);
    const std::size_t base = static_cast<std::size_t>(row) * features.width;
    const detail::FeatureRow f = detail::featureRow(features, row);
    const float* rho_row = kRho ? rho + base : nullptr;
    int col = 0;
    while (col < width) {
      const int k = l[col];
      const int end = detail::labelRunEnd(l, col, width);
      if (k >= 0) {
        if (k > max_label) {
          max_label = k;
          if (static_cast<std::size_t>(k) >= sums.size()) {
            sums.resize(std::max(static_cast<std::size_t>(k) + 1, 2 * sums.size()));
          }
        }
        FitTotals& s = sums[static_cast<std::size_t>(k)];
        if (kDepth && s.n == 0.0) s.reference = Eigen::Vector3d(f.x[col], f.y[col], f.z[col]);
        const double run = end - col;
        s.n += run;
        s.u += 0.5 * run * (col + end - 1);
        s.v += run * row;
        float m[detail::kRunSums] = {};
        detail::addRunSums<kRho, kDepth, kDepth>(
            f, rho_row, width, col, end, static_cast<float>(s.reference.x()),
            static_cast<float>(s.reference.y()), static_cast<float>(s.reference.z()), m);
        s.color += Eigen::Vector3d(m[detail::kSumR], m[detail::kSumG], m[detail::kSumB]);
        s.density += m[detail::kSumDensity];
        if constexpr (kDepth) {
          const float* moments = m + detail::kSumX;  // x, y, z, xx, xy, xz, yy, yz, zz
          s.position += Eigen::Vector3d(moments[0], moments[1], moments[2]);
          double* c = s.scatter.data();  // symmetric: column-major = row-major
          c[0] += moments[3];
          c[1] += moments[4];
          c[2] += moments[5];
          c[3] += moments[4];
          c[4] += moments[6];
          c[5] += moments[7];
          c[6] += moments[5];
          c[7] += moments[7];
          c[8] += moments[8];
          s.normal += Eigen::Vector3d(m[detail::kSumNx], m[detail::kSumNy], m[detail::kSumNz]);
        }
      }
      col = end;
    }
  }
  return max_label;
}

// The fit's accumulation for each kind of input, built for the vector units of the CPU.
DASP_VECTOR_CLONES int accumulateFitAny(const cv::Mat& labels, const PixelFeatures& features,
                                        const float* rho, std::vector<FitTotals>& sums) {
  if (features.hasDepth()) {
    return rho != nullptr ? accumulateFit<true, true>(labels, features, rho, sums)
                          : accumulateFit<true, false>(labels, features, rho, sums);
  }
  return rho != nullptr ? accumulateFit<false, true>(labels, features, rho, sums)
                        : accumulateFit<false, false>(labels, features, rho, sums);
}

}  // namespace

std::vector<Superpixel> fitSuperpoints(const cv::Mat& labels, const PixelFeatures& features,
                                       const cv::Mat& density, float radius_m,
                                       float depth_exponent) {
  if (labels.type() != CV_32SC1 || labels.cols != features.width ||
      labels.rows != features.height) {
    throw std::invalid_argument("fitSuperpoints: labels must be CV_32SC1 of the features' size");
  }
  if (!density.empty() && (density.type() != CV_32FC1 || density.size() != labels.size())) {
    throw std::invalid_argument("fitSuperpoints: density must be CV_32FC1 of the labels' size");
  }
  const bool depth = features.hasDepth();
  const float* rho = density.empty() ? nullptr : density.ptr<float>();
  // One pass over the labels: the label count is the largest label seen plus one.
  std::vector<FitTotals> sums(1024);
  const int max_label = accumulateFitAny(labels, features, rho, sums);
  sums.resize(static_cast<std::size_t>(max_label + 1));
  std::vector<Superpixel> out(sums.size());
  for (std::size_t k = 0; k < sums.size(); ++k) {
    const FitTotals& s = sums[k];
    Superpixel& sp = out[k];
    sp.id = static_cast<int>(k);
    sp.radius_m = radius_m;
    if (s.n <= 0.0) continue;
    sp.pixel_count = static_cast<int>(s.n);
    sp.u = static_cast<float>(s.u / s.n);
    sp.v = static_cast<float>(s.v / s.n);
    sp.color = (s.color / s.n).cast<float>();
    sp.density = static_cast<float>(s.density / s.n);
    if (!depth) continue;
    const Eigen::Vector3d mean = s.position / s.n;
    sp.position = (s.reference + mean).cast<float>();
    sp.radius_m = radiusAtDepth(radius_m, sp.position.z(), depth_exponent);
    const Eigen::Matrix3d cov = s.scatter / s.n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(cov);  // closed form: per-superpixel cost must not grow with K
    const Eigen::Vector3d w = solver.eigenvalues().cwiseMax(0.0);  // ascending
    // Plane-fit normal (eq. 3.22) where the points span a plane; for fewer than 3 points or
    // points on a line (second principal variance under 1 % of the first) the mean pixel normal.
    const bool plane = s.n >= 3.0 && w(1) > 0.01 * w(2);
    Eigen::Vector3d normal = plane ? Eigen::Vector3d(solver.eigenvectors().col(0)) : s.normal;
    if (!(normal.norm() > 0.0)) normal = -Eigen::Vector3d::UnitZ();
    normal.normalize();
    if (normal.dot(sp.position.cast<double>()) > 0.0) normal = -normal;
    sp.normal = normal.cast<float>();
    // 2-sigma ellipsoid axes (d, b, a) = 2 (sqrt w1, sqrt w2, sqrt w3).
    const double d = 2.0 * std::sqrt(w(0));
    const double b = 2.0 * std::sqrt(w(1));
    const double a = 2.0 * std::sqrt(w(2));
    sp.thickness = static_cast<float>(2.0 * d);
    sp.eccentricity =
        a > 0.0 ? static_cast<float>(std::sqrt(std::max(0.0, 1.0 - b * b / (a * a)))) : 0.0f;
    sp.flatness =
        a > 0.0 ? static_cast<float>(std::sqrt(std::max(0.0, 1.0 - d * d / (a * a)))) : 0.0f;
    sp.area_m2 = static_cast<float>(kPiD * a * b);
  }
  return out;
}

}  // namespace dasp
