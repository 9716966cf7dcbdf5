#pragma once
/// @file compare.hpp
/// Several calibration methods on the same positions, with the figures users compare them by.

#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"

namespace accelcal {

struct CompareOptions {
  /// Methods to run, in order. Empty: every method that fits `base.model`.
  std::vector<SolverMethod> methods;
  /// Model, gravity, initialisation and solver settings shared by all methods (`method` ignored).
  /// `base.outliers` screens the positions once, by the maximum-likelihood fit (kJoint), before
  /// any method runs; every method is then fitted to, and measured on, the same positions (a
  /// baseline fit could otherwise find other outliers, and its figures cover other positions).
  CalibrationOptions base;
  /// Refit without each position in turn to predict it (m extra fits per method).
  bool leave_one_out = true;
  /// A known calibration (e.g. a simulation's truth): each method then gets paper 001's e_T, e_b.
  std::optional<ModelParameters> reference;
};

/// Paper 001 eq. (20): e_T = ‖vec(T − T_c)‖ / 6 · 100 %, over the six entries of the
/// upper-triangular (z-first) form of both matrices, and e_b = ‖b − b_c‖ / 3 · 100 %. Absolute
/// differences, as in the paper, so the figures read as percent only for calibrations in
/// g-normalised units (K ≈ I).
struct ParameterErrors {
  double e_T_percent = 0;
  double e_b_percent = 0;
};
ParameterErrors SunXuErrors(const ModelParameters& reference, const ModelParameters& estimate);

/// One method's outcome. When the method cannot run on the data (too few positions, unobservable
/// geometry, no convergence), `error` says why and the figures are absent.
struct MethodComparison {
  SolverMethod method = SolverMethod::kJoint;
  std::optional<std::string> error;
  CalibrationResult result;
  /// Paper 001 Table 2: mean and standard deviation of |f_k|²/g² (the "modular square").
  double modular_square_mean = 0, modular_square_std = 0;
  double gravity_norm_rms = 0;  ///< RMS of |f_k| − g over the positions used
  /// RMS of |f_k| − g with position k predicted by a fit without it; absent when not requested or
  /// when a fit without some position failed (then `leave_one_out_error` says which).
  std::optional<double> leave_one_out_rms;
  std::optional<std::string> leave_one_out_error;
  /// The held-out figures measure the estimator, not the solver: maximum-likelihood solvers whose
  /// full fit agrees with an earlier one to 1e-8 relative (the same optimum) take its held-out
  /// figures instead of refitting m times; this names that method.
  std::optional<SolverMethod> leave_one_out_from;
  std::optional<ParameterErrors> against_reference;  ///< when CompareOptions::reference is set
};

/// The methods' outcomes and the positions they share.
struct Comparison {
  std::vector<MethodComparison> methods;  ///< in the order run
  /// Indices (0-based, into the readings) of the positions every method was fitted to and
  /// measured on: all, less those the screening excluded. Each result's per-position vectors
  /// (directions, residuals) follow this order.
  std::vector<int> positions_used;
  /// The screening's findings (CompareOptions::base.outliers; positions index the readings) and
  /// its note (why it could not run, or positions it could not test).
  std::vector<OutlierFinding> outliers;
  std::string outlier_note;
};

/// Every method that fits `model`, the default order of the comparison.
std::vector<SolverMethod> MethodsFor(ModelKind model);

/// Runs the methods. Throws std::invalid_argument for invalid options (including a method that
/// does not fit the model); data problems are reported per method, never thrown.
Comparison CompareMethods(const std::vector<Vec3>& readings, const CompareOptions& options);

}  // namespace accelcal
