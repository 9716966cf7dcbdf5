#include "statistics/outliers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "statistics/student_t.hpp"

namespace accelcal::internal {

OutlierFinding Screening::Finding(int index) const {
  OutlierFinding finding;
  finding.position = index;
  finding.t = t[std::size_t(index)];
  finding.threshold = StudentTTwoSidedQuantile(per_position_probability, degrees_of_freedom);
  finding.degrees_of_freedom = degrees_of_freedom;
  finding.normal_residual = e[std::size_t(index)];
  finding.scatter = scatter;
  return finding;
}

namespace {

// The leverages h_k = u_kᵀ S⁻¹ u_k on the model's P free parameters only (S⁻¹ is the identity on
// the fixed ones, where u_k has no business); lazyProduct keeps the fixed-size product off Eigen's
// GEMV path (measured: half the instructions; one GEMM over all rows, a triangular factor, or the
// symmetric half as scalar loops cost more).
template <int P>
std::vector<double> Leverages(const InformationRows& rows, const Mat12& S_inverse,
                              const std::vector<int>& cols) {
  Eigen::Matrix<double, P, P> M;
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) M(i, j) = S_inverse(cols[i], cols[j]);
  }
  const auto m = static_cast<std::size_t>(rows.U.rows());
  std::vector<double> h(m);
  Eigen::Matrix<double, P, 1> u;
  for (std::size_t k = 0; k < m; ++k) {
    for (int i = 0; i < P; ++i) u(i) = rows.U(static_cast<Eigen::Index>(k), cols[i]);
    h[k] = u.dot(M.lazyProduct(u));
  }
  return h;
}

}  // namespace

Screening ScreenPositions(const InformationRows& rows, const Mat12& S_inverse, ModelKind model,
                          const std::vector<Vec3>& residuals, double signal,
                          double false_alarm_probability) {
  Screening out;
  const int m = static_cast<int>(residuals.size());
  const int P = NumParameters(model);
  const int nu = m - P;
  if (nu < 2) {
    out.note = "outlier screening needs at least " + std::to_string(P + 2) + " positions for the " +
               std::string(ToString(model)) + " model, got " + std::to_string(m);
    return out;
  }
  out.e.resize(static_cast<std::size_t>(m));
  double sum2 = 0;
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    out.e[i] = residuals[i].dot(rows.normals[i]);
    sum2 += out.e[i] * out.e[i];
  }
  const double s2 = sum2 / nu;
  out.ran = true;
  out.scatter = std::sqrt(s2);
  out.degrees_of_freedom = nu - 1;
  out.per_position_probability = false_alarm_probability / m;  // Bonferroni
  out.t.assign(static_cast<std::size_t>(m), std::nan(""));
  // Positions fitted to round-off (simulated exact data) have no scatter to test against.
  const double round_off = 64 * std::numeric_limits<double>::epsilon() * signal;
  if (!(s2 > round_off * round_off)) return out;

  const std::vector<int>& cols = ActiveColumns(model);
  const std::vector<double> leverages =
      cols.size() == 9 ? Leverages<9>(rows, S_inverse, cols) : Leverages<12>(rows, S_inverse, cols);
  std::vector<int> untested;
  std::vector<double> scaled;  // |e_k| / √(1 − h_k), for the robust scale
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double h = leverages[i];
    if (!(1.0 - h > 1e-9)) {
      untested.push_back(k + 1);
      scaled.push_back(0.0);
      continue;
    }
    scaled.push_back(std::abs(out.e[i]) / std::sqrt(1.0 - h));
    const double r2 = out.e[i] * out.e[i] / (s2 * (1.0 - h));
    const double t = r2 >= nu ? INFINITY : std::sqrt(r2 * (nu - 1) / (nu - r2));
    out.t[i] = std::copysign(t, out.e[i]);
    if (out.most_discordant < 0 || t > std::abs(out.t[std::size_t(out.most_discordant)])) {
      out.most_discordant = k;
    }
  }
  if (out.most_discordant >= 0) {
    const double t_max = std::abs(out.t[std::size_t(out.most_discordant)]);
    out.significant = StudentTTwoSidedP(t_max, nu - 1) < out.per_position_probability;
    std::vector<double> sorted = scaled;
    std::nth_element(sorted.begin(), sorted.begin() + m / 2, sorted.end());
    const double robust_scale = 1.4826 * sorted[std::size_t(m / 2)];
    const double v_max = *std::max_element(scaled.begin(), scaled.end()) / robust_scale;
    out.suspicious = !(StudentTTwoSidedP(v_max, nu - 1) >= out.per_position_probability);
  }
  if (!untested.empty()) {
    out.note = "position";
    out.note += untested.size() > 1 ? "s " : " ";
    for (std::size_t i = 0; i < untested.size(); ++i) {
      out.note += (i ? ", " : "") + std::to_string(untested[i]);
    }
    out.note += " not screened: the other positions do not determine the fit without them";
  }
  return out;
}

}  // namespace accelcal::internal
