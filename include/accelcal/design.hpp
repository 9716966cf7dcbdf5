#pragma once
/// @file design.hpp
/// Before recording: the Cramér-Rao bound of a planned set of positions for a nominal device.
///
/// Readings p_k = μ(θ, g c_k) + v_k with v_k ~ N(0, diag(s²)) and unknown directions c_k. The
/// Fisher information of θ with the directions as nuisance parameters is
///     I = Σ_k u_k u_kᵀ / σ_k²,   σ_k² = Σ_i n_ki² s_i²,
/// with u_k and the fitted surface's normal n_k as in the covariance of calibrate.hpp (the whitened
/// projector gives the same normal-direction form). CRLB = I⁻¹: no unbiased estimator does better;
/// the maximum-likelihood solvers reach it when the noise is the same on every axis (else a
/// weighted fit would).

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "accelcal/bias_drift.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/model.hpp"
#include "accelcal/names.hpp"
#include "accelcal/thermal.hpp"

namespace accelcal {

struct PlannedUncertainty {
  ModelKind model = ModelKind::kLinear;
  Frame frame = Frame::kXFirst;  ///< the device's frame: parameter order of `crlb`
  /// P x P, flat parameter order of the frame (frame.hpp); empty when not observable.
  Eigen::MatrixXd crlb;
  ModelParameters std;      ///< 1σ of each parameter in the layout of ModelParameters (0: absent)
  double rcond = 0;         ///< reciprocal condition of the (scaled) information matrix
  bool observable = false;  ///< rcond ≥ 1e-10, the threshold calibrate refuses below
  std::string weakest;      ///< the least determined parameter when rcond < 1e-6, else empty
};

/// The CRLB of `directions` (unit vectors, body frame) for `device` (K triangular as its frame
/// says) with per-axis noise `sigma_raw` of one averaged reading [raw]. Throws
/// std::invalid_argument for non-unit directions or non-positive noise.
PlannedUncertainty PredictUncertainty(const ModelParameters& device, ModelKind model,
                                      double gravity, const std::vector<Vec3>& directions,
                                      const Vec3& sigma_raw);

/// What a drifting bias (bias_drift.hpp) costs a plan: the positions recorded in the order given,
/// evenly spaced in time, and the bias of `bias_model` fitted with the rest (CRLB of θ and D with
/// the directions as nuisance parameters, as PredictUncertainty's).
struct PlannedDriftCost {
  BiasModel bias_model;
  bool observable = false;  ///< the drift and the parameters are determined together
  /// Per flat parameter of the device's frame: 1σ with the drift fitted over 1σ with a constant
  /// bias (≥ 1: the part of each parameter the drift could take up).
  Eigen::VectorXd inflation;
  int worst = -1;  ///< the flat index of the largest inflation
  /// 1σ of D [raw] (3 × J; linear: per minute with one position a minute).
  Eigen::MatrixXd drift_sigma;
};
/// Throws as PredictUncertainty; a constant bias_model is refused (std::invalid_argument).
PlannedDriftCost PredictDriftCost(const ModelParameters& device, ModelKind model, double gravity,
                                  const std::vector<Vec3>& directions, const Vec3& sigma_raw,
                                  const BiasModel& bias_model);

/// What a temperature schedule determines (thermal.hpp): `directions` recorded at each of
/// `temperatures_c` (the same orientations at every temperature), the parameters of `degrees` in
/// T − T_ref (T_ref the temperatures' mean) fitted with the directions as nuisance parameters.
/// The device is taken in the x-first frame (ChangeFrame), with temperature coefficients of 0:
/// the bound depends on them only through the small change of K they make.
struct PlannedThermal {
  ThermalDegrees degrees;
  double t_ref_c = 0;
  bool observable = false;  ///< the temperatures and orientations determine every coefficient
  /// CRLB of the thermal flat vector (ThermalSlots order, x-first) and its 1σ [raw units per K^d].
  Eigen::MatrixXd crlb;
  Eigen::VectorXd sigma;
};
/// Temperatures closer than this count as one in a schedule: a degree d needs d + 1 of them (a
/// difference at a temperature sensor's resolution determines no slope, however exact the
/// arithmetic).
inline constexpr double kMinThermalSeparation_K = 0.1;
/// Throws std::invalid_argument for fewer than 1 temperature, a non-finite one, or degrees the
/// model cannot take. Not observable with fewer than degrees.Max() + 1 temperatures
/// kMinThermalSeparation_K apart.
PlannedThermal PredictThermalUncertainty(const ModelParameters& device, ModelKind model,
                                         double gravity, const std::vector<Vec3>& directions,
                                         const std::vector<double>& temperatures_c,
                                         const Vec3& sigma_raw, const ThermalDegrees& degrees);

/// D-optimal choice of `count` distinct positions out of `candidates`: maximises det I (the
/// volume of the CRLB's confidence ellipsoid shrinks with it; invariant to the parameters' units).
/// Greedy start (regularised until `count` ≥ P), then Fedorov exchanges until no swap of a chosen
/// and an unchosen candidate increases det I. Returns the chosen indices in increasing order.
/// Throws std::invalid_argument when count exceeds the candidates or is below the model's minimum.
std::vector<int> ChooseDOptimal(const ModelParameters& device, ModelKind model, double gravity,
                                const std::vector<Vec3>& candidates, const Vec3& sigma_raw,
                                int count);

/// A-optimal choice of `count` distinct positions out of `candidates`: minimises the trace of the
/// CRLB with the parameters in the device's metric (relative change of the prediction, as for
/// LogDetInformation: the trace then does not depend on the parameters' units; it is the mean
/// squared prediction error the parameters' uncertainty causes, summed over them). Starts from the
/// D-optimal choice and exchanges a chosen and an unchosen candidate while the trace falls (exact
/// rank-2 Woodbury update). Returns the chosen indices in increasing order; throws as
/// ChooseDOptimal.
std::vector<int> ChooseAOptimal(const ModelParameters& device, ModelKind model, double gravity,
                                const std::vector<Vec3>& candidates, const Vec3& sigma_raw,
                                int count);

/// Trace of the CRLB of `directions` in the metric of ChooseAOptimal (+inf when singular).
double TraceCrlb(const ModelParameters& device, ModelKind model, double gravity,
                 const std::vector<Vec3>& directions, const Vec3& sigma_raw);

/// log det of the information matrix of `directions`, the parameters measured in the device's
/// metric (relative change of the prediction, as in TerminationType): comparable between sets for
/// the same device, model and noise; −inf when singular.
double LogDetInformation(const ModelParameters& device, ModelKind model, double gravity,
                         const std::vector<Vec3>& directions, const Vec3& sigma_raw);

/// Which optimality ChoosePositions seeks.
enum class DesignCriterion {
  kD,  ///< "d": maximise det I (ChooseDOptimal)
  kA,  ///< "a": minimise the trace of the CRLB in the device's metric (ChooseAOptimal)
};
std::string_view ToString(DesignCriterion criterion);
template <>
struct EnumNames<DesignCriterion> {
  static constexpr std::pair<DesignCriterion, std::string_view> kTable[] = {
      {DesignCriterion::kD, "d"}, {DesignCriterion::kA, "a"}};
};

/// What Design evaluates: a nominal device and the noise of one averaged reading, and
/// optionally the choice of `choose` positions out of the given ones.
struct DesignOptions {
  ModelParameters device;
  Frame frame = Frame::kXFirst;  ///< the device's frame (its K's shape, frame.hpp)
  ModelKind model = ModelKind::kLinear;
  double gravity = 0;             ///< > 0, in the device's specific-force unit
  Vec3 sigma_raw = Vec3::Zero();  ///< 1σ per axis of one averaged reading [raw], > 0
  int choose = 0;                 ///< 0: evaluate every position; else choose this many
  DesignCriterion criterion = DesignCriterion::kD;
  /// Cap on the exchange sweeps of the choice (Fedorov exchanges; each sweep makes the best
  /// single swap): reached, the summary says so.
  int max_exchanges = 100;
  /// Why the options are invalid (messages name the fields), or nothing.
  std::optional<std::string> Validate() const;
};

/// How Design ended, with its stopping rule as a formula.
struct DesignSummary {
  int exchanges = 0;  ///< swaps made by the choice (0 without one)
  bool converged = true;
  /// "no exchange improves det I by more than 1e-10 relative" (or the trace), or the cap.
  std::string termination_message;
};

struct DesignResult {
  /// Indices of the chosen positions in the given order (all of them without a choice).
  std::vector<int> chosen;
  /// Against paper 000's 18 positions, with a choice: (det I / det I_yang18)^(1/P) and
  /// tr CRLB_yang18 / tr CRLB (the device's metric); > 1 is better. NaN without a choice.
  double d_efficiency = std::numeric_limits<double>::quiet_NaN();
  double a_efficiency = std::numeric_limits<double>::quiet_NaN();
  PlannedUncertainty planned;  ///< the bound of the chosen positions
  DesignSummary summary;
};

/// The Cramér-Rao bound of `directions` (unit vectors in the device's body frame), or of the best
/// `options.choose` of them. A platform-frame device (a known-orientation fit, full K) is
/// evaluated as the same linear device in its x-first form, the directions rotated with it; its
/// quadratic model has no orientation-free equivalent and is refused. Throws
/// std::invalid_argument for invalid options or directions.
DesignResult Design(const std::vector<Vec3>& directions, const DesignOptions& options);

/// The most positions "random:N" makes (a count from an option is bounded before allocation).
inline constexpr int kMaxRandomPositions = 100000;

/// Named observation schemes: "yang18" (paper 000 Table 2), "six" (±x, ±y, ±z), "random:N" or
/// "random:N:SEED" (uniform on the sphere, seed 1 by default; N from 1 to kMaxRandomPositions).
/// std::nullopt for another name; InputError (naming the spec) for a "random:" spec that is not
/// one.
std::optional<std::vector<Vec3>> SchemeDirections(std::string_view name);

}  // namespace accelcal
