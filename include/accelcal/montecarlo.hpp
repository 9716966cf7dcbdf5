#pragma once
/// @file montecarlo.hpp
/// Monte Carlo of a simulated calibration scenario against the Cramér-Rao bound (paper 000 §5,
/// Table 4). Each run draws its own noise from (seed, run index), so the statistics do not depend
/// on how many threads share the runs.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "accelcal/frame.hpp"

namespace accelcal {

/// A simulated calibration: the truth, the positions and the noise of one averaged reading.
struct Scenario {
  std::string name;
  ModelParameters truth;
  ModelKind model = ModelKind::kQuadratic;
  double gravity = 9.8;          ///< in the specific-force unit
  std::vector<Vec3> directions;  ///< unit, body frame
  Vec3 sigma_raw = Vec3::Ones();
  /// > 0: each run draws this many new paper 001 §4.1 attitudes (SunXu2020Directions) instead of
  /// using `directions`; results are then the flat parameters' errors and paper 001's e_T, e_b
  /// (no Table 4).
  int random_attitudes = 0;
  Frame frame = Frame::kXFirst;  ///< the frame of `truth` (and of the fits)
};

/// "yang2012": paper 000 Table 3 truth (quadratic), Table 2's 18 positions, 10 µg/√Hz at 100 Hz
/// for 60 s per position (docs/errata.md#000-table4: 1.291 µg per axis per averaged reading), g
/// = 9.8 m/s². "sunxu2020": paper 001 eq. (19) (T_a upper-triangular, z-first; linear model, g
/// units), 300 new Gaussian attitudes per run, σ = 0.1 g.
std::optional<Scenario> ScenarioByName(std::string_view name);

/// The most runs of one Monte Carlo: each keeps its outcome until the statistics are taken, so
/// the count from an option is bounded before allocation (issue 16).
inline constexpr int kMaxMonteCarloRuns = 1000000;

struct MonteCarloOptions {
  int runs = 500;  ///< 2 to kMaxMonteCarloRuns
  std::uint64_t seed = 1;
  CalibrationOptions calibration;  ///< model, gravity and frame are taken from the scenario
  /// Give each run its true per-axis noise (CalibrationOptions::reading_sigmas), as a raw log's
  /// intervals would; false: the covariance comes from the residuals.
  bool known_noise = true;
  /// 0: all hardware threads; at most 4 per hardware thread are started (runs are seeded by
  /// their index, so the result is the same for every thread count; more threads only contend,
  /// and creating thousands of them failed).
  int threads = 0;
  /// Called after runs finish with (runs done, runs in total), one call at a time, the count
  /// increasing; from the worker threads, so it must be cheap and thread-safe in what it touches
  /// (e.g. a progress bar). Empty: not called.
  std::function<void(int done, int total)> progress;
};

/// Statistics of one error over the runs. Fixed positions (yang2012): paper 000 Table 4's
/// engineering errors in its units. Random attitudes (sunxu2020): the flat parameters in the
/// scenario's frame (g units).
struct ErrorStatistics {
  std::string name;  ///< ka_x … tau_yx … p0_x … k2_x, or the frame's slot names (K_zz, b_z, …)
  std::string unit;  ///< ppm, arcsec, ug, g/g^2; or g/g (K), g (b)
  double min = 0, max = 0, mean = 0, median = 0, std = 0;
  double rmse = 0;  ///< root mean square error (bias and spread)
  /// 1σ bound in the same unit (propagated from the parameters' CRLB); with random attitudes
  /// the root of the mean over the runs of each run's bound (its own attitudes).
  double crlb = 0;
  double ratio = 0;       ///< std / crlb
  double rmse_ratio = 0;  ///< rmse / crlb
};

struct MonteCarloResult {
  std::string scenario;
  SolverMethod method = SolverMethod::kJoint;
  int runs = 0;
  int failed = 0;  ///< runs that threw or did not converge (left out of the statistics)
  std::vector<ErrorStatistics> errors;
  /// Fraction of (run, flat parameter) pairs whose reported 1σ interval covers the truth.
  double coverage = 0;
  double inclination_error_rms_arcsec = 0;  ///< angle between estimated and true directions
  /// Paper 001 eq. (20), means over the runs [%], and the mean error of diag(T_a) (z-first form)
  /// beside σ²/T_ii, the incidental-parameter bias docs/errata.md#001-ml-bias expects at this noise
  /// level.
  double e_T_percent_mean = 0, e_b_percent_mean = 0;
  Vec3 diag_T_bias = Vec3::Zero();
  Vec3 diag_T_bias_expected = Vec3::Zero();
  Vec3 diag_T_bias_standard_error = Vec3::Zero();
};

/// Throws std::invalid_argument for invalid options (fewer than 2 runs, bad calibration options).
MonteCarloResult RunMonteCarlo(const Scenario& scenario, const MonteCarloOptions& options);

}  // namespace accelcal
