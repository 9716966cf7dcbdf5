#pragma once
/// @file model_selection.hpp
/// Which model do the data support? The quadratic model always lowers the in-sample residual (it
/// has three more parameters), so the choice is made on held-out error: both models are fitted
/// with leave-one-position-out validation (CalibrationOptions::cross_validate) and compared on the
/// same positions, and the quadratic model is kept only on evidence (SelectModel). When the
/// quadratic model cannot be fitted or validated (too few positions, unobservable, not
/// converged), the linear model is kept and the reason says why.

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"

namespace accelcal {

/// One-sided probability of the paired test of SelectModel: the chance that a linear device's
/// held-out improvement passes it by noise alone (5 %: t quantile 1.645 for many positions).
inline constexpr double kHeldOutImprovementAlpha = 0.05;
/// Two-sided probability, over all three squared coefficients together (Bonferroni: 5 %/3 per
/// coefficient), that a linear device has some |k2_i/σ_i| beyond the threshold of SelectModel
/// (2.39 for many positions, 2.64 at 18 degrees of freedom).
inline constexpr double kSquaredCoefficientAlpha = 0.05;

struct ModelSelection {
  ModelKind chosen = ModelKind::kLinear;
  std::string reason;  ///< why `chosen`, with the numbers that decided
  CalibrationResult linear;
  /// Absent when the quadratic model cannot be fitted; quadratic_error says why.
  std::optional<CalibrationResult> quadratic;
  std::string quadratic_error;
  /// k2_i / σ(k2_i) of the quadratic fit (t-statistics; NaN without a covariance): |t| of 2 or
  /// less means the squared coefficient is not distinguishable from zero.
  Vec3 k2_t = Vec3::Constant(std::nan(""));

  /// The model whose outlier screening chose the positions of both fits: the quadratic one when
  /// it can be fitted (SelectModel says why), else the linear one (then there is no comparison).
  ModelKind screened_with = ModelKind::kLinear;
  /// Indices (0-based, into the readings) of the positions both fits use and the held-out
  /// comparison is over: all, less those the screening excluded (as Comparison::positions_used).
  std::vector<int> positions_used;
  /// The paired comparison of SelectModel over `positions_used` (NaN unless both models were
  /// validated): the mean of d_k = e_lin,k² − e_quad,k² (held-out |f_k| − g of each model,
  /// squared) [unit²], positive when the quadratic model predicts better; its standard error
  /// sd(d)/√n; and the threshold improvement_se · t_{n−1}(1 − kHeldOutImprovementAlpha) that the
  /// improvement must exceed.
  double improvement = std::nan("");
  double improvement_se = std::nan("");
  double improvement_threshold = std::nan("");
  /// The |k2_i/σ_i| that some squared coefficient must exceed (SelectModel; NaN when the
  /// quadratic model was not fitted with a covariance).
  double k2_t_threshold = std::nan("");

  const CalibrationResult& chosen_result() const {
    return chosen == ModelKind::kQuadratic ? *quadratic : linear;
  }
};

/// Fits both models with `options` (its model and cross_validate are overridden) and chooses.
///
/// Same positions: the quadratic fit screens the positions (options.outliers) as Calibrate does,
/// and the linear model is fitted to the positions it kept, with no screening of its own; the
/// linear result lists the quadratic screening's findings in its `outliers`, its per-position
/// vectors still one entry per reading. Why the quadratic screening: the quadratic model holds
/// under both hypotheses being compared (it contains the linear one), so its screening's
/// false-alarm probability holds whichever model is true; the linear screening's holds only for
/// a linear device, and on a device with real squared terms it may exclude the positions that
/// show them, the very evidence for the quadratic model (the union of both screenings'
/// exclusions would too). The quadratic result is therefore exactly Calibrate's with model
/// kQuadratic; the linear one differs from Calibrate's only where the two screenings disagree,
/// and its findings carry the quadratic fit's statistics. When the quadratic model cannot be
/// fitted or validated, nothing is compared and the linear result is Calibrate's own.
///
/// Evidence: over the n kept positions, d_k = e_lin,k² − e_quad,k² pairs the two models' held-out
/// errors position by position (a paired test: the positions' own difficulty, common to both,
/// cancels). The quadratic model is chosen only when both
///   - mean(d) > t_{n−1}(1 − kHeldOutImprovementAlpha) · sd(d)/√n: the held-out improvement is
///     larger than its sampling error (one-sided, 1.645 for many positions), not a lower RMS by
///     chance (a linear device's quadratic fit predicts better in about 13 % of runs); and
///   - max_i |k2_i/σ_i| > t_ν(1 − kSquaredCoefficientAlpha/6), ν the quadratic fit's degrees of
///     freedom: some squared coefficient is significant (two-sided 5 % after Bonferroni over the
///     three; Student's t because σ_i comes from the residuals' scatter, or from the samples
///     scaled up by the scatter ratio: at least as wide as the normal's 2.39). An improvement
///     that no coefficient explains is not the squared terms'.
/// Measured on simulated linear devices (random positions, Yang 2012 noise): the quadratic model
/// chosen in 3 of 1000 runs on 30 positions and 12 of 1000 on 18 (a lower held-out RMS alone:
/// 126 and 104); real squared terms (paper 000 Table 3) found in 185 of 200 runs on 18 positions
/// (test_model_selection.cpp).
/// Throws as Calibrate() does when the linear model cannot be fitted.
ModelSelection SelectModel(const std::vector<Vec3>& readings, CalibrationOptions options);

/// One step of SelectBiasModel: a richer bias model against the one chosen so far.
struct BiasModelStep {
  BiasModel simpler, richer;
  /// Why the richer model was not compared (it cannot be fitted, validated, or converge); empty
  /// when it was.
  std::string error;
  /// Positions of the comparison (0-based): those the richer model's screening kept.
  std::vector<int> positions_used;
  /// Held-out rms |f| − g of each over positions_used, and the paired comparison of SelectModel:
  /// mean of d_k = e_simpler,k² − e_richer,k², its standard error and the threshold it must pass.
  double simpler_rms = std::nan(""), richer_rms = std::nan("");
  double improvement = std::nan(""), improvement_se = std::nan("");
  double improvement_threshold = std::nan("");
  /// The Wald statistic of what the richer model adds (W = (A d)ᵀ (A C Aᵀ)⁻¹ (A d), d its drift
  /// coefficients, C their covariance): against the constant bias, A = I (any drift); against
  /// a linear or spline bias, A the second differences of the knot biases (a bias that is not
  /// linear in time). Its threshold is χ²_dof(1 − kBiasDriftAlpha).
  double wald = std::nan("");
  double wald_threshold = std::nan("");
  int wald_dof = 0;
  bool accepted = false;
};

/// Probability, for the Wald test of SelectBiasModel, that a bias without the richer model's
/// change passes it by noise alone.
inline constexpr double kBiasDriftAlpha = 0.05;

struct BiasModelSelection {
  BiasModel chosen;
  std::string reason;        ///< why `chosen`, with the numbers of the step that decided
  CalibrationResult result;  ///< the chosen model's fit (screened and validated as Calibrate's)
  std::vector<BiasModelStep> steps;
};

/// The bias models SelectBiasModel tries, in order: constant, linear, then spline:3, spline:4 …
/// up to spline:6 while the fit keeps at least 10 degrees of freedom (m − P − 3J ≥ 10).
std::vector<BiasModel> BiasModelCandidates(int positions, ModelKind model);

/// Which bias model do the data support? Forward selection over BiasModelCandidates with the rule
/// of SelectModel: from the constant bias, each richer model is fitted with its screening and
/// validation, the model chosen so far is fitted to the positions it kept, and the richer one is
/// chosen only when both
///   - its held-out error is lower beyond sampling error (the paired one-sided test of
///     SelectModel at kHeldOutImprovementAlpha), and
///   - what it adds is significant: W > χ²_dof(1 − kBiasDriftAlpha) (BiasModelStep::wald).
/// A richer model that fails either is passed over and the next compared with the model chosen
/// so far (a spline can follow a warm-up that levels off, which no straight line does). The
/// reason names the chosen model's evidence and every candidate passed over with why.
/// options.bias_model is ignored;
/// without position_times_s (or with a single position time) the constant bias is kept and the
/// reason says why. Throws as Calibrate() does when the constant bias cannot be fitted.
BiasModelSelection SelectBiasModel(const std::vector<Vec3>& readings, CalibrationOptions options);

/// A calibration with the model asked for, and the comparison that goes with it.
struct ModelChoice {
  CalibrationResult result;
  /// With `auto_model`, or a quadratic fit with cross-validation: the comparison of both models
  /// (the quadratic fit is compared with the linear one even when asked for, so that a quadratic
  /// model the data do not support can be said to be so).
  std::optional<ModelSelection> selection;
};
/// `auto_model`: the model SelectModel chooses (options.model is ignored; cross-validation
/// required). Otherwise options.model, compared as above when quadratic. Throws as Calibrate().
ModelChoice CalibrateChoosingModel(const std::vector<Vec3>& readings,
                                   const CalibrationOptions& options, bool auto_model);

}  // namespace accelcal
