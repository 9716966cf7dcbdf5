#include "accelcal/bias_drift.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "accelcal/frame.hpp"

namespace accelcal {

namespace {
constexpr double kLinearTimeUnit_s = 60.0;  // D of the linear basis in raw per minute

// The hat function B_j of equally spaced knots at t, held at the end knots' values outside.
double Hat(const std::vector<double>& knots, std::size_t j, double t) {
  const std::size_t K = knots.size();
  if (t <= knots.front()) return j == 0 ? 1.0 : 0.0;
  if (t >= knots.back()) return j + 1 == K ? 1.0 : 0.0;
  if (j > 0 && t > knots[j - 1] && t <= knots[j]) {
    return (t - knots[j - 1]) / (knots[j] - knots[j - 1]);
  }
  if (j + 1 < K && t >= knots[j] && t < knots[j + 1]) {
    return (knots[j + 1] - t) / (knots[j + 1] - knots[j]);
  }
  return 0.0;
}
}  // namespace

std::string ToString(const BiasModel& model) {
  std::string name(NameOf(model.kind));
  if (model.kind == BiasModelKind::kSpline) name += ":" + std::to_string(model.knots);
  return name;
}

std::optional<BiasModel> BiasModelFromString(std::string_view text) {
  const std::size_t colon = text.find(':');
  const std::optional<BiasModelKind> kind = FromName<BiasModelKind>(text.substr(0, colon));
  if (!kind) return std::nullopt;
  BiasModel model;
  model.kind = *kind;
  if (*kind != BiasModelKind::kSpline) {
    if (colon != std::string_view::npos) return std::nullopt;
    return model;
  }
  if (colon == std::string_view::npos) return std::nullopt;
  const std::string_view digits = text.substr(colon + 1);
  int knots = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), knots);
  if (ec != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
  if (knots < 2 || knots > kMaxBiasKnots) return std::nullopt;
  model.knots = knots;
  return model;
}

BiasTimeBasis BiasTimeBasis::For(const BiasModel& model, const std::vector<double>& times_s) {
  BiasTimeBasis basis;
  basis.model = model;
  for (double t : times_s) {
    if (!std::isfinite(t)) throw std::invalid_argument("a position's time is not finite");
  }
  if (model.constant()) return basis;
  if (times_s.size() < 2) {
    throw std::invalid_argument("a bias that changes with time needs the times of two positions");
  }
  const auto [lo, hi] = std::minmax_element(times_s.begin(), times_s.end());
  if (!(*hi > *lo)) {
    throw std::invalid_argument("the positions' times span no time: a drift cannot be told");
  }
  basis.t_ref_s =
      std::accumulate(times_s.begin(), times_s.end(), 0.0) / static_cast<double>(times_s.size());
  if (model.kind == BiasModelKind::kSpline) {
    const int K = model.knots;
    for (int j = 0; j < K; ++j) {
      basis.knots_s.push_back(j + 1 == K ? *hi : *lo + (*hi - *lo) * j / (K - 1));
    }
  }
  return basis;
}

Eigen::VectorXd BiasTimeBasis::Evaluate(double t_s) const {
  Eigen::VectorXd phi(size());
  switch (model.kind) {
    case BiasModelKind::kConstant:
      break;
    case BiasModelKind::kLinear:
      phi(0) = (t_s - t_ref_s) / kLinearTimeUnit_s;
      break;
    case BiasModelKind::kSpline:
      for (std::size_t j = 1; j < knots_s.size(); ++j) {
        phi(static_cast<Eigen::Index>(j - 1)) = Hat(knots_s, j, t_s) - Hat(knots_s, j, t_ref_s);
      }
      break;
  }
  return phi;
}

Vec3 BiasDrift::Offset(double t_s) const {
  if (D.cols() == 0) return Vec3::Zero();
  return D * basis.Evaluate(t_s);
}

Vec3 BiasDrift::BiasSigma(double t_s, const int bias_slots[3]) const {
  const Eigen::Index J = D.cols();
  const Eigen::Index P = covariance.rows() - 3 * J;
  if (covariance.size() == 0 || P <= 0) return Vec3::Constant(std::nan(""));
  const Eigen::VectorXd phi = basis.Evaluate(t_s);
  Vec3 sigma;
  for (int i = 0; i < 3; ++i) {
    // b_i(t) = b_i + Σ_j D_ij φ_j: a linear function of the entries at these indices.
    Eigen::VectorXd w = Eigen::VectorXd::Zero(covariance.rows());
    w(bias_slots[i]) = 1.0;
    for (Eigen::Index j = 0; j < J; ++j) w(P + i * J + j) = phi(j);
    sigma(i) = std::sqrt(std::max(0.0, w.dot(covariance * w)));
  }
  return sigma;
}

BiasDrift MirrorAxes(const BiasDrift& drift, ModelKind model) {
  // P v = (v_z, −v_y, v_x): row i of the result is sign[i] times row from[i].
  constexpr int kFrom[3] = {2, 1, 0};
  constexpr double kSign[3] = {1.0, -1.0, 1.0};
  BiasDrift out = drift;
  const Eigen::Index J = drift.D.cols();
  for (int i = 0; i < 3; ++i) out.D.row(i) = kSign[i] * drift.D.row(kFrom[i]);
  if (drift.random_walk) out.random_walk = MirrorAxes(*drift.random_walk).cwiseAbs();
  if (drift.covariance.size() == 0) return out;
  const Eigen::Index P = NumParameters(model);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(P + 3 * J, P + 3 * J);
  M.topLeftCorner(P, P) = MirrorSigns(model).asDiagonal();
  for (int i = 0; i < 3; ++i) {
    for (Eigen::Index j = 0; j < J; ++j) M(P + i * J + j, P + kFrom[i] * J + j) = kSign[i];
  }
  out.covariance = M * drift.covariance * M.transpose();
  return out;
}

}  // namespace accelcal
