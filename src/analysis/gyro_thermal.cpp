// The gyroscope's offsets over temperature (gyro_thermal.hpp).
#include "analysis/gyro_thermal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "accelcal/error.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/thermal_calibration.hpp"
#include "core/text_format.hpp"
#include "statistics/held_out.hpp"
#include "statistics/student_t.hpp"

namespace accelcal::internal {

namespace {

/// Below this span of the still positions' temperatures a change per K is not determined by a
/// tumble's still means: their noise over 1 K is already the size of a MEMS gyro's change.
constexpr double kMinSpan_K = 1.0;

// The temperatures of one log at its samples, or empty when it has none.
const std::vector<double>* Temperatures(const RawLog& log) {
  if (log.temperature_c.size() != log.samples.size()) return nullptr;
  for (double t : log.temperature_c) {
    if (std::isfinite(t)) return &log.temperature_c;
  }
  return nullptr;
}

// One degree's fit: per axis, the weighted least squares of the still means on
// [1, u, …, u^D, (f)], u = ΔT / scale.
struct DegreeFit {
  int degree = 0;
  std::vector<Vec3> b;                   // b_1 … b_D [raw per K^d]
  Eigen::MatrixXd covariance;            // of b, 3D x 3D, under the sample noise
  std::vector<double> heldout_whitened;  // per still: ‖e_loo‖ over its axes, whitened
  std::vector<double> heldout_raw;       // the same in raw units
  bool validated = true;                 // every still's held-out error defined
  double chi2 = 0;
  int dof = 0;
};

std::optional<DegreeFit> FitDegree(const std::vector<GyroStill>& stills,
                                   const std::vector<double>& dT, double scale, int degree,
                                   bool g_sensitivity) {
  const auto n = static_cast<Eigen::Index>(stills.size());
  const Eigen::Index p = 1 + degree + (g_sensitivity ? 3 : 0);
  if (n < p + 1) return std::nullopt;
  DegreeFit out;
  out.degree = degree;
  out.b.assign(static_cast<std::size_t>(degree), Vec3::Zero());
  out.covariance = Eigen::MatrixXd::Zero(3 * degree, 3 * degree);
  out.heldout_whitened.assign(stills.size(), 0.0);
  out.heldout_raw.assign(stills.size(), 0.0);
  out.dof = static_cast<int>(3 * (n - p));
  for (int a = 0; a < 3; ++a) {
    Eigen::MatrixXd X(n, p);
    Eigen::VectorXd y(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const GyroStill& s = stills[static_cast<std::size_t>(k)];
      const double w = 1.0 / s.sigma_mean_raw(a);
      const double u = dT[static_cast<std::size_t>(k)] / scale;
      double power = 1;
      for (int d = 0; d <= degree; ++d) {
        X(k, d) = w * power;
        power *= u;
      }
      if (g_sensitivity) {
        for (int c = 0; c < 3; ++c) X(k, 1 + degree + c) = w * s.f(c);
      }
      y(k) = w * s.mean_raw(a);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
    if (qr.rank() < p) return std::nullopt;
    const Eigen::VectorXd beta = qr.solve(y);
    const Eigen::MatrixXd N_inverse =
        (X.transpose() * X).ldlt().solve(Eigen::MatrixXd::Identity(p, p));
    const Eigen::VectorXd r = y - X * beta;
    out.chi2 += r.squaredNorm();
    for (int d = 1; d <= degree; ++d) {
      const double unit = std::pow(scale, d);  // c_d u^d = (c_d / s^d) ΔT^d
      out.b[static_cast<std::size_t>(d - 1)](a) = beta(d) / unit;
      for (int e = 1; e <= degree; ++e) {
        out.covariance(3 * (d - 1) + a, 3 * (e - 1) + a) =
            N_inverse(d, e) / (unit * std::pow(scale, e));
      }
    }
    // Leave one still out, exactly for least squares: e_k = r_k / (1 − h_kk).
    for (Eigen::Index k = 0; k < n; ++k) {
      const double h = X.row(k).dot(N_inverse * X.row(k).transpose());
      if (!(h < 1 - 1e-9)) {
        out.validated = false;
        continue;
      }
      const double e = r(k) / (1 - h);
      const auto i = static_cast<std::size_t>(k);
      out.heldout_whitened[i] += e * e;
      const double raw = e * stills[i].sigma_mean_raw(a);
      out.heldout_raw[i] += raw * raw;
    }
  }
  for (std::size_t i = 0; i < stills.size(); ++i) {
    out.heldout_whitened[i] = std::sqrt(out.heldout_whitened[i]);
    out.heldout_raw[i] = std::sqrt(out.heldout_raw[i]);
  }
  return out;
}

double Rms(const std::vector<double>& e) {
  double sum = 0;
  for (double x : e) sum += x * x;
  return std::sqrt(sum / static_cast<double>(e.size()));
}

}  // namespace

GyroThermal FitGyroThermal(const std::vector<GyroStill>& stills,
                           const std::vector<double>& temperatures_c,
                           const GyroThermalOptions& options, bool g_sensitivity) {
  if (temperatures_c.size() != stills.size()) {
    throw std::invalid_argument("FitGyroThermal: one temperature per still position");
  }
  if (options.degree && (*options.degree < 0 || *options.degree > kMaxThermalDegree)) {
    throw std::invalid_argument("the gyroscope's thermal degree must be from 0 to " +
                                std::to_string(kMaxThermalDegree));
  }
  if (!std::isfinite(options.t_ref_c)) {
    throw std::invalid_argument("the gyroscope's T_ref must be finite");
  }
  GyroThermal out;
  out.temperatures_c = temperatures_c;
  const auto [lo, hi] = std::minmax_element(temperatures_c.begin(), temperatures_c.end());
  out.range_c = {*lo, *hi};
  // T_ref within the temperatures fitted over (the gyro's die may run warmer than the
  // accelerometer's whose T_ref is asked for): else their mean, and said.
  out.bias.t_ref_c = options.t_ref_c;
  std::string moved;
  if (!(options.t_ref_c >= *lo && options.t_ref_c <= *hi)) {
    double sum = 0;
    for (double t : temperatures_c) sum += t;
    out.bias.t_ref_c = sum / static_cast<double>(temperatures_c.size());
    moved = Format(
        "; T_ref %.4g degC, the mean of its still positions' temperatures, as %.4g degC "
        "lies outside them",
        out.bias.t_ref_c, options.t_ref_c);
  }
  std::vector<double> dT;
  double scale = 0;
  for (double t : temperatures_c) {
    dT.push_back(t - out.bias.t_ref_c);
    scale = std::max(scale, std::abs(dT.back()));
  }
  const double span = *hi - *lo;
  const std::string what = Format(
      "the gyroscope's %zu still positions, whose temperatures span %.3g K (%.4g to %.4g "
      "degC)",
      stills.size(), span, *lo, *hi);
  const auto set = [&](const DegreeFit& fit) {
    out.bias.coefficients = fit.b;
    out.scatter_ratio = fit.dof > 0 ? std::sqrt(fit.chi2 / fit.dof) : 1.0;
    const double inflate = std::max(1.0, out.scatter_ratio);
    out.bias.covariance = inflate * inflate * fit.covariance;
    if (fit.validated) out.heldout_rms_raw = Rms(fit.heldout_raw);
  };
  if (!(span >= kMinSpan_K) || options.degree == 0) {
    if (std::optional<DegreeFit> constant = FitDegree(stills, dT, 1.0, 0, g_sensitivity)) {
      set(*constant);  // the still means' scatter about constant offsets
    }
    if (options.degree == 0) {
      out.reason = "given" + moved;
      return out;
    }
    if (options.degree) {
      throw DataError(what +
                      ", cannot determine how its offsets change with temperature: they "
                      "need " +
                      Format("%.3g", kMinSpan_K) + " K at least");
    }
    out.reason =
        what + Format(": too narrow a span to see a change (under %.3g K)", kMinSpan_K) + moved;
    return out;
  }
  if (options.degree) {
    const std::optional<DegreeFit> fit =
        FitDegree(stills, dT, scale, *options.degree, g_sensitivity);
    if (!fit) {
      throw DataError(what + Format(", do not determine a polynomial of degree %d in "
                                    "temperature%s: it needs more positions or more distinct "
                                    "temperatures",
                                    *options.degree,
                                    g_sensitivity ? " beside the g-sensitivity" : ""));
    }
    set(*fit);
    out.reason = "given" + moved;
    return out;
  }
  // Chosen from 0 up, as SelectThermalDegrees chooses the accelerometer's degrees.
  std::optional<DegreeFit> current = FitDegree(stills, dT, scale, 0, g_sensitivity);
  if (!current) {
    throw DataError(what + ", are too few to fit the offsets at all");
  }
  std::vector<int> all(stills.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  std::string steps;
  for (int degree = 1; degree <= kMaxThermalDegree; ++degree) {
    const std::optional<DegreeFit> richer = FitDegree(stills, dT, scale, degree, g_sensitivity);
    if (!richer || !richer->validated || !current->validated) {
      steps += Format("; degree %d not determined by these positions", degree);
      break;
    }
    const Paired paired =
        PairedImprovement(current->heldout_whitened, richer->heldout_whitened, all);
    const double threshold = StudentTTwoSidedQuantile(2 * kHeldOutImprovementAlpha,
                                                      static_cast<double>(stills.size()) - 1) *
                             paired.se;
    // The Wald statistic of the added b_D (its three axes independent).
    const Vec3& added = richer->b.back();
    const double inflate = std::max(1.0, richer->dof > 0 ? richer->chi2 / richer->dof : 1.0);
    double wald = 0;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Index i = 3 * (degree - 1) + a;
      wald += added(a) * added(a) / (inflate * richer->covariance(i, i));
    }
    const double wald_threshold = ChiSquareQuantile(kThermalAlpha, 3);
    const bool accepted = paired.mean > threshold && wald > wald_threshold;
    steps += Format(
        "; degree %d: held-out RMS %.3g against %.3g (raw), paired improvement %.3g %s %.3g, "
        "Wald %.3g %s %.3g",
        degree, Rms(richer->heldout_raw), Rms(current->heldout_raw), paired.mean,
        paired.mean > threshold ? ">" : "<=", threshold, wald,
        wald > wald_threshold ? ">" : "<=", wald_threshold);
    if (!accepted) break;
    current = richer;
  }
  set(*current);
  out.reason =
      Format("degree %d chosen by the still positions' held-out mean rates", current->degree) +
      steps + moved;
  return out;
}

}  // namespace accelcal::internal

namespace accelcal {

std::vector<double> GyroSampleTemperatures(const RawLog& gyro, const RawLog& accel) {
  const std::vector<double>* own = internal::Temperatures(gyro);
  const std::vector<double>* other =
      accel.samples.size() == gyro.samples.size() ? internal::Temperatures(accel) : nullptr;
  if (own == nullptr && other == nullptr) {
    throw DataError("neither the gyroscope's log " + gyro.source + " nor the accelerometer's " +
                    accel.source +
                    " has a temperature at its samples: the gyroscope's offsets over "
                    "temperature are fitted to its readings at theirs");
  }
  // One source: the gyroscope's own when it has any (its die may run warmer than the
  // accelerometer's, so a gap is not filled from the other), else the accelerometer's.
  std::vector<double> t = own != nullptr ? *own : *other;
  // The gaps: the line between the samples on either side, held beyond the ends.
  std::size_t last = t.size();  // the last sample with a temperature, none yet
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!std::isfinite(t[k])) continue;
    if (last == t.size()) {
      for (std::size_t j = 0; j < k; ++j) t[j] = t[k];
    } else {
      for (std::size_t j = last + 1; j < k; ++j) {
        const double w = static_cast<double>(j - last) / static_cast<double>(k - last);
        t[j] = (1 - w) * t[last] + w * t[k];
      }
    }
    last = k;
  }
  for (std::size_t j = last + 1; j < t.size(); ++j) t[j] = t[last];
  return t;
}

std::string GyroTemperatureSource(const RawLog& gyro, const RawLog& accel) {
  // The source GyroSampleTemperatures takes, by the same check.
  if (internal::Temperatures(gyro) != nullptr) {
    return "the gyroscope's log: " + gyro.temperature_source;
  }
  if (accel.samples.size() == gyro.samples.size() && internal::Temperatures(accel) != nullptr) {
    return "the accelerometer's log: " + accel.temperature_source;
  }
  return "";
}

}  // namespace accelcal
