#include "accelcal/system_level.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "accelcal/error.hpp"
#include "accelcal/gravity.hpp"
#include "core/text_format.hpp"

namespace accelcal {

namespace {

constexpr double kArcsec = 3.14159265358979323846 / 180.0 / 3600.0;

// The attitude coefficients' basis b(S) = (1, cos S, sin S, cos 2S, sin 2S).
Eigen::Matrix<double, 5, 1> Basis(double S) {
  const double c = std::cos(S), s = std::sin(S);
  Eigen::Matrix<double, 5, 1> b;
  b << 1.0, c, s, c * c - s * s, 2 * s * c;
  return b;
}

FourierCoefficients ToFourier(const Eigen::Matrix<double, 5, 1>& v) {
  return {v(0), v(1), v(2), v(3), v(4)};
}

// Inverse-variance weighted mean of three estimates of one quantity.
Estimate Combine(std::string name, const double values[3], const double variances[3]) {
  double w_sum = 0, wv_sum = 0;
  for (int i = 0; i < 3; ++i) {
    w_sum += 1.0 / variances[i];
    wv_sum += values[i] / variances[i];
  }
  return {std::move(name), wv_sum / w_sum, std::sqrt(1.0 / w_sum)};
}

std::string Number(double v) {
  char buf[32];
  internal::FormatTo(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The combinations w of the free parameters (`free`, the unknowns the null space of eq. (41)
// moves) that it determines, with Nᵀw = 0, in reduced row echelon form (pivots in the order of the
// unknowns), each named from `names`: e.g. ∇x/g − sin L Δβxy.
std::vector<std::pair<std::string, Eigen::Matrix<double, 6, 1>>> DeterminedCombinations(
    const Eigen::MatrixXd& null_space, const std::vector<int>& free, const char* const names[6]) {
  std::vector<std::pair<std::string, Eigen::Matrix<double, 6, 1>>> out;
  Eigen::MatrixXd Nf(null_space.cols(), static_cast<Eigen::Index>(free.size()));
  for (std::size_t j = 0; j < free.size(); ++j) Nf.col(j) = null_space.row(free[j]).transpose();
  Eigen::JacobiSVD<Eigen::MatrixXd> nsvd(Nf, Eigen::ComputeFullV);
  const Eigen::Index nrank = (nsvd.singularValues().array() > 1e-9).count();
  Eigen::MatrixXd W = nsvd.matrixV().rightCols(Nf.cols() - nrank).transpose();  // rows: w
  // Reduced row echelon form by Gauss-Jordan with partial pivoting along the columns.
  Eigen::Index row = 0;
  for (Eigen::Index col = 0; col < W.cols() && row < W.rows(); ++col) {
    Eigen::Index pivot = row;
    W.col(col).segment(row, W.rows() - row).cwiseAbs().maxCoeff(&pivot);
    pivot += row;
    if (std::abs(W(pivot, col)) < 1e-9) continue;
    W.row(row).swap(W.row(pivot));
    W.row(row) /= W(row, col);
    for (Eigen::Index other = 0; other < W.rows(); ++other) {
      if (other != row) W.row(other) -= W(other, col) * W.row(row);
    }
    ++row;
  }
  for (Eigen::Index k = 0; k < W.rows(); ++k) {
    Eigen::Matrix<double, 6, 1> w = Eigen::Matrix<double, 6, 1>::Zero();
    std::string name;
    for (std::size_t j = 0; j < free.size(); ++j) {
      const double coefficient = W(k, static_cast<Eigen::Index>(j));
      if (std::abs(coefficient) < 1e-12) continue;
      w(free[j]) = coefficient;
      const std::string term = std::abs(std::abs(coefficient) - 1.0) < 1e-12
                                   ? names[free[j]]
                                   : Number(std::abs(coefficient)) + "*" + names[free[j]];
      name += name.empty() ? (coefficient < 0 ? "-" : "") + term
                           : (coefficient < 0 ? " - " : " + ") + term;
    }
    out.emplace_back(name, w);
  }
  return out;
}

}  // namespace

ResidualErrors Wu2018Residuals() {
  ResidualErrors e;
  e.scale = Vec3(1e-4, 2e-4, -1e-4);
  e.bias_ms2 = Vec3(-1e-3, 5e-4, 1e-3);
  e.beta_xz = 5 * kArcsec;
  e.beta_yz = 10 * kArcsec;
  e.beta_zy = -5 * kArcsec;
  e.beta_xy = -10 * kArcsec;
  e.beta_yx = 5 * kArcsec;
  e.beta_zx = -5 * kArcsec;
  return e;
}

CombinedCoefficients CombinedFromResiduals(const ResidualErrors& e, double L, double g) {
  const double s = std::sin(L), c = std::cos(L);
  const double half_x = e.scale(0) / 2, half_y = e.scale(1) / 2;
  const Vec3 nabla = e.bias_ms2 / g;
  CombinedCoefficients out;
  out.x << (half_x + half_y) * c * c - (nabla(2) - e.scale(2) * s) * s,    // (21)
      nabla(0) - e.beta_xy * s + e.beta_zy * s,                            // (22)
      nabla(1) + e.beta_yx * s - e.beta_zx * s,                            // (23)
      half_x - half_y,                                                     // (24)
      (e.beta_yz - e.beta_xz) / 2;                                         // (25)
  out.pitch.mean = (nabla(2) - (e.scale(2) - half_x - half_y) * s) * c;    // (29), no base terms
  out.pitch.c1 = -(nabla(0) * s - e.beta_xy * s * s - e.beta_zy * c * c);  // (30)
  out.pitch.s1 = -(nabla(1) * s + e.beta_yx * s * s + e.beta_zx * c * c);  // (31)
  out.pitch.c2 = (half_x - half_y) * s * c;                                // (32)
  out.pitch.s2 = (e.beta_yz / 2 - e.beta_xz / 2) * s * c;                  // (33)
  out.roll.mean = (e.beta_yz / 2 + e.beta_xz / 2) * c;                     // (34), no base terms
  out.roll.s1 = nabla(0) - e.beta_xy * s;                                  // (35)
  out.roll.c1 = -nabla(1) - e.beta_yx * s;                                 // (36)
  out.roll.s2 = -(half_x - half_y) * c;                                    // (37)
  out.roll.c2 = (e.beta_yz / 2 - e.beta_xz / 2) * c;                       // (38)
  return out;
}

void SimulateSystemLevel(const SystemSimulationOptions& o,
                         const std::function<void(const SystemSample&)>& sink) {
  const double L = o.latitude_deg * 3.14159265358979323846 / 180.0;
  const double g = o.gravity_ms2 > 0 ? o.gravity_ms2 : NormalGravityWgs84_ms2(o.latitude_deg);
  const double attitude_noise = o.attitude_noise_rad >= 0 ? o.attitude_noise_rad : o.noise_ms2 / g;
  const CombinedCoefficients c = CombinedFromResiduals(o.errors, L, g);
  const ResidualErrors& e = o.errors;
  Mat33 M = Mat33::Zero();  // diag(ΔSF/SF) + ΔC_p^a of eq. (14)
  M << e.scale(0), -e.beta_xz, e.beta_xy, e.beta_yz, e.scale(1), -e.beta_yx, -e.beta_zy, e.beta_zx,
      e.scale(2);
  const Mat33 A = Mat33::Identity() + M;
  std::mt19937_64 random(o.seed);
  std::normal_distribution<double> normal;
  const auto count = static_cast<long>(std::llround(o.duration_s * o.rate_hz));
  const auto harmonic = [](const FourierCoefficients& k, double cs, double sn, double c2,
                           double s2) {
    return k.mean + k.c1 * cs + k.s1 * sn + k.c2 * c2 + k.s2 * s2;
  };
  for (long n = 0; n < count; ++n) {
    SystemSample s;
    s.t = static_cast<double>(n) / o.rate_hz;
    const double S = kEarthRate_rad_s * s.t;
    const double cs = std::cos(S), sn = std::sin(S);
    const double c2 = cs * cs - sn * sn, s2 = 2 * sn * cs;
    const Vec3 f = g * Vec3(cs * std::cos(L), sn * std::cos(L), std::sin(L));
    s.f = A * f - e.bias_ms2;
    for (int i = 0; i < 3; ++i) s.f(i) += o.noise_ms2 * normal(random);
    s.roll = harmonic(c.roll, cs, sn, c2, s2) + attitude_noise * normal(random);
    s.pitch = harmonic(c.pitch, cs, sn, c2, s2) + attitude_noise * normal(random);
    sink(s);
  }
}

std::optional<std::string> SystemLevelOptions::Validate() const {
  const double degrees = latitude_rad * 180.0 / 3.14159265358979323846;
  if (!(std::abs(degrees) < 89)) return "latitude must lie in (-89, 89) degrees";
  if (std::abs(degrees) < 1) {
    return "latitude: within 1 degree of the equator sin L vanishes and the second harmonics of "
           "the attitude errors carry no information (eq. (32), (33))";
  }
  if (!(gravity_ms2 >= 0) || !std::isfinite(gravity_ms2)) {
    return "gravity_ms2 must be positive (or 0 for normal gravity at the latitude)";
  }
  if (min_samples < 6) return "min_samples must be at least 6 (5 coefficients per fit)";
  if (!(min_platform_angle_rad > 0) || !std::isfinite(min_platform_angle_rad)) {
    return "min_platform_angle_rad must be a positive number";
  }
  if (!(rank_tolerance > 0 && rank_tolerance < 1)) return "rank_tolerance must lie in (0, 1)";
  return std::nullopt;
}

SystemLevelEstimator::SystemLevelEstimator(const SystemLevelOptions& options)
    : options_(options), latitude_(options.latitude_rad), gravity_(options.gravity_ms2) {
  if (const auto error = options.Validate()) throw std::invalid_argument(*error);
  if (gravity_ == 0) gravity_ = NormalGravityWgs84_ms2(latitude_ * 180.0 / 3.14159265358979323846);
}

void SystemLevelEstimator::Add(const SystemSample& sample) {
  const double S = kEarthRate_rad_s * sample.t;
  const Eigen::Matrix<double, 5, 1> b = Basis(S);
  const double z = 0.5 * (sample.f.squaredNorm() / (gravity_ * gravity_) - 1.0);
  gram_.noalias() += b.lazyProduct(b.transpose());
  const Vec3 y(z, sample.roll, sample.pitch);
  rhs_.noalias() += b.lazyProduct(y.transpose());
  sum_squares_ += y.cwiseAbs2();
  if (count_ > 0) difference_squares_ += (sample.f - previous_f_).cwiseAbs2();
  previous_f_ = sample.f;
  s_min_ = count_ == 0 ? S : std::min(s_min_, S);
  s_max_ = count_ == 0 ? S : std::max(s_max_, S);
  ++count_;
}

SystemLevelResult SystemLevelEstimator::Finish() const {
  if (count_ < options_.min_samples) {
    throw DataError("the series has " + std::to_string(count_) +
                    " samples; the system-level fit needs at least " +
                    std::to_string(options_.min_samples));
  }
  if (s_max_ - s_min_ < options_.min_platform_angle_rad) {
    const double hours = options_.min_platform_angle_rad / kEarthRate_rad_s / 3600;
    throw DataError("the series covers " + Number((s_max_ - s_min_) / kEarthRate_rad_s / 3600) +
                    " h of platform rotation; the Earth-rate harmonics need at least " +
                    Number(std::ceil(hours)) + " h (24 h recommended)");
  }
  SystemLevelResult r;
  r.samples = count_;
  r.gravity_ms2 = gravity_;
  const double n = static_cast<double>(count_);
  const Eigen::LDLT<Eigen::Matrix<double, 5, 5>> gram(gram_);
  const Eigen::Matrix<double, 5, 5> gram_inverse =
      gram.solve(Eigen::Matrix<double, 5, 5>::Identity());
  const Eigen::Matrix<double, 5, 3> coefficients = gram.solve(rhs_);
  // Residual variance of each fit: Σy² − cᵀ(Σ b y), over n − 5 degrees of freedom.
  Vec3 variance;
  for (int k = 0; k < 3; ++k) {
    variance(k) = std::max(0.0, sum_squares_(k) - coefficients.col(k).dot(rhs_.col(k))) / (n - 5);
  }
  // Specific force: H = T b with T = diag(1, −cos L, −cos L, cos² L, cos² L).
  const double cL = std::cos(latitude_), sL = std::sin(latitude_);
  Eigen::Matrix<double, 5, 1> t_inverse;
  t_inverse << 1.0, -1.0 / cL, -1.0 / cL, 1.0 / (cL * cL), 1.0 / (cL * cL);
  r.noise_ms2 = (difference_squares_ / (2.0 * (n - 1))).cwiseSqrt();
  r.x1_noise_correction =
      options_.correct_x1_noise ? r.noise_ms2.squaredNorm() / (2 * gravity_ * gravity_) : 0.0;
  r.x = t_inverse.cwiseProduct(coefficients.col(0));
  r.x(0) -= r.x1_noise_correction;
  const Eigen::Matrix<double, 5, 5> x_cov =
      variance(0) * t_inverse.asDiagonal() * gram_inverse * t_inverse.asDiagonal();
  r.x_std = x_cov.diagonal().cwiseSqrt();
  r.roll = ToFourier(coefficients.col(1));
  r.pitch = ToFourier(coefficients.col(2));
  r.roll_std = ToFourier((variance(1) * gram_inverse.diagonal()).cwiseSqrt());
  r.pitch_std = ToFourier((variance(2) * gram_inverse.diagonal()).cwiseSqrt());
  const auto var = [&](int fit, int k) { return variance(fit) * gram_inverse(k, k); };

  // Groups 1 and 2 (eq. (39), (40)).
  {
    const double values[3] = {r.x(3), -r.roll.s2 / cL, r.pitch.c2 / (sL * cL)};
    const double variances[3] = {x_cov(3, 3), var(1, 4) / (cL * cL),
                                 var(2, 3) / (sL * sL * cL * cL)};
    r.determined.push_back(Combine("dSFx/(2SFx) - dSFy/(2SFy)", values, variances));
  }
  {
    const double values[3] = {r.x(4), r.roll.c2 / cL, r.pitch.s2 / (sL * cL)};
    const double variances[3] = {x_cov(4, 4), var(1, 3) / (cL * cL),
                                 var(2, 4) / (sL * sL * cL * cL)};
    r.determined.push_back(Combine("(dbeta_yz - dbeta_xz)/2", values, variances));
  }

  // Eq. (41): unknowns (∇x/g, ∇y/g, Δβyx, Δβzx, Δβxy, Δβzy) from (x2, x3, δφ1s, δφ1c, δθ1c,
  // δθ1s), weighted by the inverse covariance of those coefficients.
  static const char* const kNames[6] = {"nabla_x/g", "nabla_y/g", "dbeta_yx",
                                        "dbeta_zx",  "dbeta_xy",  "dbeta_zy"};
  Eigen::Matrix<double, 6, 6> A;
  A << 1, 0, 0, 0, -sL, sL,              // x2 (22)
      0, 1, sL, -sL, 0, 0,               // x3 (23)
      1, 0, 0, 0, -sL, 0,                // δφ1s (35)
      0, -1, -sL, 0, 0, 0,               // δφ1c (36)
      -sL, 0, 0, 0, sL * sL, cL * cL,    // δθ1c (30)
      0, -sL, -sL * sL, -cL * cL, 0, 0;  // δθ1s (31)
  Eigen::Matrix<double, 6, 1> y;
  y << r.x(1), r.x(2), r.roll.s1, r.roll.c1, r.pitch.c1, r.pitch.s1;
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.block<2, 2>(0, 0) = x_cov.block<2, 2>(1, 1);
  C(2, 2) = var(1, 2);
  C(3, 3) = var(1, 1);
  C(2, 3) = C(3, 2) = variance(1) * gram_inverse(2, 1);
  C(4, 4) = var(2, 1);
  C(5, 5) = var(2, 2);
  C(4, 5) = C(5, 4) = variance(2) * gram_inverse(1, 2);
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> whitening(C);
  const Eigen::Matrix<double, 6, 6> Aw = whitening.matrixL().solve(A);
  const Eigen::Matrix<double, 6, 1> yw = whitening.matrixL().solve(y);
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(Aw, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const auto& sv = svd.singularValues();
  r.rank = 0;
  for (int i = 0; i < 6; ++i) r.rank += sv(i) > options_.rank_tolerance * sv(0) ? 1 : 0;
  const Eigen::MatrixXd null_space = svd.matrixV().rightCols(6 - r.rank);
  Eigen::Matrix<double, 6, 6> pinv = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < r.rank; ++i) {
    pinv += svd.matrixV().col(i) * (1.0 / sv(i)) * svd.matrixU().col(i).transpose();
  }
  const Eigen::Matrix<double, 6, 1> solution = pinv * yw;
  const Eigen::Matrix<double, 6, 6> covariance = pinv * pinv.transpose();
  const auto estimate = [&](const std::string& name, const Eigen::Matrix<double, 6, 1>& w) {
    r.determined.push_back({name, w.dot(solution), std::sqrt(w.dot(covariance * w))});
  };
  std::vector<int> free;  // parameters the null space moves
  for (int i = 0; i < 6; ++i) {
    if (null_space.rows() > 0 && null_space.cols() > 0 && null_space.row(i).norm() > 1e-9) {
      free.push_back(i);
      r.undetermined.emplace_back(kNames[i]);
    } else {
      estimate(kNames[i], Eigen::Matrix<double, 6, 1>::Unit(i));
    }
  }
  if (!free.empty()) {
    for (const auto& [name, w] : DeterminedCombinations(null_space, free, kNames))
      estimate(name, w);
  }
  // The closed form's summary: the specific-force fit's sums of squares and conditioning.
  const Eigen::Matrix<double, 5, 1> scale = gram_.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 5, 5>> scaled(
      scale.asDiagonal() * gram_ * scale.asDiagonal(), Eigen::EigenvaluesOnly);
  r.summary.termination = TerminationType::kClosedForm;
  r.summary.initial_cost = sum_squares_(0);
  r.summary.final_cost = variance(0) * (n - 5);
  r.summary.termination_message = internal::Format(
      "closed form: normal equations of %ld samples (Gram matrix reciprocal condition %.3g); "
      "eq. (41) rank %d of 6 = #{sigma_i > %.0e sigma_1}",
      count_, scaled.eigenvalues()(0) / scaled.eigenvalues()(4), r.rank, options_.rank_tolerance);
  return r;
}

}  // namespace accelcal
