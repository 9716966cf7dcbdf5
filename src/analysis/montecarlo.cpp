#include "accelcal/montecarlo.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <Eigen/Geometry>

#include "accelcal/compare.hpp"
#include "accelcal/design.hpp"
#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "core/parallel.hpp"

namespace accelcal {

namespace {

constexpr int kErrors = 14;

// The engineering quantities of paper 000 Table 4 in its units: ka [ppm of ka], τ [arcsec],
// p0 [µg], k2 [g/g²].
Eigen::Matrix<double, kErrors, 1> Engineering(const ModelParameters& params, double gravity,
                                              const EngineeringParameters& truth) {
  const EngineeringParameters e = ToEngineering(params, gravity);
  Eigen::Matrix<double, kErrors, 1> v;
  const Vec3 ka_ppm = e.scale_factor.cwiseQuotient(truth.scale_factor) * 1e6;
  const Vec3 p0_ug = e.bias_force / gravity * 1e6;
  v << ka_ppm, e.tau_yx * kArcsecPerRad, e.tau_zx * kArcsecPerRad, e.tau_zy * kArcsecPerRad,
      e.tau_yy * kArcsecPerRad, e.tau_zz * kArcsecPerRad, p0_ug, e.k2_g_per_g2;
  return v;
}

const char* const kNames[kErrors] = {"ka_x",   "ka_y",   "ka_z",   "tau_yx", "tau_zx",
                                     "tau_zy", "tau_yy", "tau_zz", "p0_x",   "p0_y",
                                     "p0_z",   "k2_x",   "k2_y",   "k2_z"};
const char* const kUnits[kErrors] = {"ppm",    "ppm", "ppm", "arcsec", "arcsec", "arcsec", "arcsec",
                                     "arcsec", "ug",  "ug",  "ug",     "g/g^2",  "g/g^2",  "g/g^2"};

struct RunOutcome {
  bool ok = false;
  Eigen::VectorXd parameter_error;  // random attitudes: flat, the scenario frame's order
  Eigen::VectorXd crlb_variance;    // random attitudes: this run's bound (diagonal)
  double e_T = 0, e_b = 0;
  Vec3 diag_T_error = Vec3::Zero();
  Eigen::Matrix<double, kErrors, 1> error;
  int covered = 0, parameters = 0;
  double inclination_sum2 = 0;
};

RunOutcome OneRun(const Scenario& s, const CalibrationOptions& options, std::uint64_t seed,
                  const Eigen::Matrix<double, kErrors, 1>& truth_eng,
                  const EngineeringParameters& truth) {
  RunOutcome out;
  const std::vector<Vec3> directions =
      s.random_attitudes > 0 ? SunXu2020Directions(s.random_attitudes, seed ^ 0x9e3779b97f4a7c15u)
                             : s.directions;
  const std::vector<Vec3> readings =
      SimulatePositions(s.truth, s.gravity, directions, s.sigma_raw, seed);
  CalibrationResult r;
  try {
    r = Calibrate(readings, options);
  } catch (const std::exception&) {
    return out;
  }
  if (!r.summary.converged()) return out;
  out.ok = true;
  if (s.random_attitudes == 0) {
    out.error = Engineering(r.params, s.gravity, truth) - truth_eng;
  } else {
    const auto& slots = ParameterSlots(s.model, s.frame);
    out.parameter_error = Pack(r.params, slots) - Pack(s.truth, slots);
    const PlannedUncertainty bound =
        PredictUncertainty(s.truth, s.model, s.gravity, directions, s.sigma_raw);
    if (bound.observable) out.crlb_variance = bound.crlb.diagonal();
  }
  const ParameterErrors sx = SunXuErrors(s.truth, r.params);
  out.e_T = sx.e_T_percent;
  out.e_b = sx.e_b_percent;
  out.diag_T_error = ChangeFrame(r.params.K, Frame::kZFirst).K.diagonal() -
                     ChangeFrame(s.truth.K, Frame::kZFirst).K.diagonal();
  if (r.covariance.size() > 0) {
    const auto& slots = ParameterSlots(s.model, s.frame);  // the covariance's order
    const Eigen::VectorXd e = Pack(r.params, slots) - Pack(s.truth, slots);
    for (Eigen::Index i = 0; i < e.size(); ++i) {
      out.covered += std::abs(e(i)) <= std::sqrt(r.covariance(i, i)) ? 1 : 0;
      ++out.parameters;
    }
  }
  for (std::size_t k = 0; k < directions.size(); ++k) {
    const double angle =
        std::atan2(r.directions[k].cross(directions[k]).norm(), r.directions[k].dot(directions[k]));
    out.inclination_sum2 += angle * angle;
  }
  return out;
}

// CRLB of the engineering errors: J C Jᵀ with J = ∂(engineering)/∂θ by central differences (the
// map is smooth; steps of 1e-7 relative leave errors far below the bound's own precision).
Eigen::Matrix<double, kErrors, 1> EngineeringBound(const Scenario& s,
                                                   const EngineeringParameters& truth) {
  const PlannedUncertainty planned =
      PredictUncertainty(s.truth, s.model, s.gravity, s.directions, s.sigma_raw);
  Eigen::Matrix<double, kErrors, 1> bound =
      Eigen::Matrix<double, kErrors, 1>::Constant(std::nan(""));
  if (!planned.observable) return bound;
  const Eigen::VectorXd theta = Pack(s.truth, s.model);
  Eigen::MatrixXd J(kErrors, theta.size());
  for (Eigen::Index j = 0; j < theta.size(); ++j) {
    const double h = 1e-7 * std::max(1e-3, std::abs(theta(j)));
    Eigen::VectorXd plus = theta, minus = theta;
    plus(j) += h;
    minus(j) -= h;
    J.col(j) = (Engineering(Unpack(plus, s.model), s.gravity, truth) -
                Engineering(Unpack(minus, s.model), s.gravity, truth)) /
               (2 * h);
  }
  const Eigen::MatrixXd C = J * planned.crlb * J.transpose();
  for (int i = 0; i < kErrors; ++i) bound(i) = std::sqrt(std::max(0.0, C(i, i)));
  return bound;
}

// min, max, mean, median, std and RMSE of `values` (sorted in place) against `crlb`.
ErrorStatistics Statistics(std::string name, std::string unit, std::vector<double>* values,
                           double crlb) {
  ErrorStatistics st;
  st.name = std::move(name);
  st.unit = std::move(unit);
  st.crlb = crlb;
  std::vector<double>& v = *values;
  if (v.size() < 2) return st;
  const auto n = static_cast<double>(v.size());
  double sum = 0, sum2 = 0;
  for (double x : v) {
    sum += x;
    sum2 += x * x;
  }
  st.mean = sum / n;
  double ss = 0;
  for (double x : v) ss += (x - st.mean) * (x - st.mean);
  st.std = std::sqrt(ss / (n - 1));
  st.rmse = std::sqrt(sum2 / n);
  std::sort(v.begin(), v.end());
  st.min = v.front();
  st.max = v.back();
  st.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  st.ratio = st.std / st.crlb;
  st.rmse_ratio = st.rmse / st.crlb;
  return st;
}

// Random attitudes: the flat parameters' errors against the mean of the runs' own bounds.
std::vector<ErrorStatistics> ParameterStatistics(const Scenario& s,
                                                 const std::vector<RunOutcome>& outcomes) {
  const auto& slots = ParameterSlots(s.model, s.frame);
  std::vector<ErrorStatistics> out;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const auto index = static_cast<Eigen::Index>(i);
    std::vector<double> values;
    double variance = 0;
    int bounded = 0;
    for (const RunOutcome& o : outcomes) {
      if (!o.ok) continue;
      values.push_back(o.parameter_error(index));
      if (o.crlb_variance.size() > 0) {
        variance += o.crlb_variance(index);
        ++bounded;
      }
    }
    const double crlb = bounded > 0 ? std::sqrt(variance / bounded) : std::nan("");
    const bool is_K = slots[i].group == ParameterGroup::kK;
    out.push_back(Statistics(std::string(slots[i].name), is_K ? "g/g" : "g", &values, crlb));
  }
  return out;
}

}  // namespace

std::optional<Scenario> ScenarioByName(std::string_view name) {
  if (name == "sunxu2020") {
    Scenario s;
    s.name = "sunxu2020";
    s.truth.K = SunXu2020Ta();
    s.truth.bias = SunXu2020Ba();
    s.model = ModelKind::kLinear;
    s.gravity = 1.0;
    s.random_attitudes = 300;
    s.directions = SunXu2020Directions(300, 1);  // for the bound: one typical draw
    s.sigma_raw = Vec3::Constant(kSunXu2020Sigma_g);
    s.frame = Frame::kZFirst;
    return s;
  }
  if (name != "yang2012") return std::nullopt;
  Scenario s;
  s.name = "yang2012";
  s.truth = Yang2012Truth();
  s.model = ModelKind::kQuadratic;
  s.gravity = kYang2012Gravity_ms2;
  s.directions = Yang18Directions();
  s.sigma_raw = Yang2012SigmaRaw(s.truth);
  return s;
}

MonteCarloResult RunMonteCarlo(const Scenario& scenario, const MonteCarloOptions& options) {
  if (options.runs < 2 || options.runs > kMaxMonteCarloRuns) {
    throw std::invalid_argument("a Monte Carlo needs 2 to " + std::to_string(kMaxMonteCarloRuns) +
                                " runs");
  }
  CalibrationOptions calibration = options.calibration;
  calibration.model = scenario.model;
  calibration.gravity = scenario.gravity;
  calibration.cross_validate = false;
  calibration.frame = scenario.frame;
  const std::size_t positions = scenario.random_attitudes > 0
                                    ? static_cast<std::size_t>(scenario.random_attitudes)
                                    : scenario.directions.size();
  if (options.known_noise) calibration.reading_sigmas.assign(positions, scenario.sigma_raw);
  if (auto why = calibration.Validate()) throw OptionError(*why);

  const EngineeringParameters truth = ToEngineering(scenario.truth, scenario.gravity);
  const Eigen::Matrix<double, kErrors, 1> truth_eng =
      Engineering(scenario.truth, scenario.gravity, truth);
  std::vector<RunOutcome> outcomes(static_cast<std::size_t>(options.runs));
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  const int threads =
      std::min({options.runs, 4 * static_cast<int>(hardware),
                options.threads > 0 ? options.threads : static_cast<int>(hardware)});
  // Runs are independent and seeded by their index; each fills its own slot.
  std::mutex progress_mutex;
  int done = 0;
  internal::ParallelFor(options.runs, threads, [&](int run) {
    outcomes[static_cast<std::size_t>(run)] =
        OneRun(scenario, calibration, options.seed * 1000003u + static_cast<std::uint64_t>(run),
               truth_eng, truth);
    if (options.progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      options.progress(++done, options.runs);
    }
  });

  MonteCarloResult result;
  result.scenario = scenario.name;
  result.method = calibration.method;
  result.runs = options.runs;
  std::vector<std::vector<double>> values(kErrors);
  long covered = 0, parameters = 0;
  double inclination_sum2 = 0;
  long inclination_count = 0;
  for (const RunOutcome& o : outcomes) {
    if (!o.ok) {
      ++result.failed;
      continue;
    }
    for (int i = 0; i < kErrors; ++i) values[static_cast<std::size_t>(i)].push_back(o.error(i));
    covered += o.covered;
    parameters += o.parameters;
    inclination_sum2 += o.inclination_sum2;
    inclination_count += static_cast<long>(positions);
    result.e_T_percent_mean += o.e_T;
    result.e_b_percent_mean += o.e_b;
    result.diag_T_bias += o.diag_T_error;
  }
  const int ok_runs = options.runs - result.failed;
  if (ok_runs > 0) {
    result.e_T_percent_mean /= ok_runs;
    result.e_b_percent_mean /= ok_runs;
    result.diag_T_bias /= ok_runs;
    Vec3 spread = Vec3::Zero();
    for (const RunOutcome& o : outcomes) {
      if (o.ok) spread += (o.diag_T_error - result.diag_T_bias).cwiseAbs2();
    }
    result.diag_T_bias_standard_error =
        (spread / std::max(1, ok_runs - 1)).cwiseSqrt() / std::sqrt(static_cast<double>(ok_runs));
  }
  const Mat33 T = ChangeFrame(scenario.truth.K, Frame::kZFirst).K;
  const double sigma2 = scenario.sigma_raw.squaredNorm() / 3.0;
  for (int i = 0; i < 3; ++i) result.diag_T_bias_expected(i) = sigma2 / T(i, i);
  // Table 4 for fixed positions; random attitudes: the flat parameters, and e_T, e_b above.
  const bool table4 = scenario.random_attitudes == 0;
  const Eigen::Matrix<double, kErrors, 1> bound =
      table4 ? EngineeringBound(scenario, truth)
             : Eigen::Matrix<double, kErrors, 1>::Constant(std::nan(""));
  for (int i = 0; i < kErrors && table4; ++i) {
    result.errors.push_back(
        Statistics(kNames[i], kUnits[i], &values[static_cast<std::size_t>(i)], bound(i)));
  }
  if (!table4) result.errors = ParameterStatistics(scenario, outcomes);
  result.coverage = parameters > 0 ? static_cast<double>(covered) / static_cast<double>(parameters)
                                   : std::nan("");
  result.inclination_error_rms_arcsec =
      inclination_count > 0
          ? std::sqrt(inclination_sum2 / static_cast<double>(inclination_count)) * kArcsecPerRad
          : std::nan("");
  return result;
}

}  // namespace accelcal
