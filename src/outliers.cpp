#include "outliers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "accelcal/frame.hpp"
#include "solver_common.hpp"
#include "student_t.hpp"

namespace accelcal::internal {

OutlierFinding Screening::Finding(int index) const {
  OutlierFinding finding;
  finding.position = index;
  finding.t = t[std::size_t(index)];
  finding.threshold = threshold;
  finding.degrees_of_freedom = degrees_of_freedom;
  finding.normal_residual = e[std::size_t(index)];
  finding.scatter = scatter;
  return finding;
}

Screening ScreenPositions(const CalibrationResult& result, double false_alarm_probability) {
  Screening out;
  const int m = static_cast<int>(result.directions.size());
  const int P = NumParameters(result.model);
  const int nu = m - P;
  if (nu < 2) {
    out.note = "outlier screening needs at least " + std::to_string(P + 2) + " positions for the " +
               std::string(ToString(result.model)) + " model, got " + std::to_string(m);
    return out;
  }
  // The information rows are written in the x-first layout; the z-first fit is the x-first fit of
  // the mirrored problem, and normal residuals and leverages do not depend on the gauge.
  const bool mirror = result.frame == Frame::kZFirst;
  const ModelParameters params = mirror ? MirrorAxes(result.params) : result.params;
  std::vector<Vec3> dirs = result.directions;
  if (mirror) {
    for (Vec3& c : dirs) c = MirrorAxes(c);
  }
  // The rows need only the parameters and directions; the readings only give their number.
  const std::vector<Vec3> placeholders(static_cast<std::size_t>(m), Vec3::Zero());
  const Problem problem{placeholders, result.gravity, result.model};
  const InformationRows rows = ReducedInformationRows(problem, params, dirs);

  // Leverages h_k = u_kᵀ S⁻¹ u_k over the free columns, Jacobi-scaled (h does not depend on the
  // columns' scale, the factorisation's accuracy does).
  const std::vector<int>& cols = ActiveColumns(result.model);
  Eigen::MatrixXd U(m, P);
  for (int j = 0; j < P; ++j) U.col(j) = rows.U.col(cols[static_cast<std::size_t>(j)]);
  const Eigen::VectorXd scale = U.colwise().norm().cwiseMax(1e-300).cwiseInverse().transpose();
  U = U * scale.asDiagonal();
  const Eigen::LLT<Eigen::MatrixXd> llt(U.transpose() * U);
  if (llt.info() != Eigen::Success) {
    out.note = "outlier screening skipped: the information matrix is singular";
    return out;
  }
  const Eigen::MatrixXd W = llt.matrixL().solve(U.transpose());  // h_k = |W.col(k)|²
  out.e.resize(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    out.e[i] =
        (mirror ? MirrorAxes(result.residuals[i]) : result.residuals[i]).dot(rows.normals[i]);
  }
  double sum2 = 0;
  for (double e : out.e) sum2 += e * e;
  const double s2 = sum2 / nu;
  out.ran = true;
  out.scatter = std::sqrt(s2);
  out.degrees_of_freedom = nu - 1;
  out.threshold = StudentTTwoSidedQuantile(false_alarm_probability / m, nu - 1);  // Bonferroni
  out.t.assign(static_cast<std::size_t>(m), std::nan(""));
  // Positions fitted to round-off (simulated exact data) have no scatter to test against.
  double signal = 0;
  for (int i = 0; i < 3; ++i) {
    signal = std::max(
        signal, std::abs(result.params.K(i, i)) * result.gravity + std::abs(result.params.bias(i)));
  }
  const double round_off = 64 * std::numeric_limits<double>::epsilon() * signal;
  if (!(s2 > round_off * round_off)) return out;

  std::vector<int> untested;
  std::vector<double> scaled;  // |e_k| / √(1 − h_k), for the robust scale
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double h = W.col(k).squaredNorm();
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
  std::vector<double> sorted = scaled;
  std::nth_element(sorted.begin(), sorted.begin() + m / 2, sorted.end());
  const double robust_scale = 1.4826 * sorted[std::size_t(m / 2)];
  for (double v : scaled) out.suspicious |= v > out.threshold * robust_scale;
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
