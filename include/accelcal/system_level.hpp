#pragma once
/// @file system_level.hpp
/// Paper 003 (Wu et al. 2018) §5: system-level calibration of the accelerometer residual errors of
/// a space-stable (gimbaled) INS on a static, level base at latitude L, from the specific-force
/// error and the horizontal attitude errors over about a day.
///
/// Specific force (eq. (18)-(27)): with the platform angle S = ω_ie t, the ideal specific force in
/// the platform frame is g u, u = (cos S cos L, sin S cos L, sin L) (eq. (19)), and the observation
///     z = ½(|f̂^p/g|² − 1) = H x + v,  H = [1, −u_x, −u_y, u_x² − u_y², 2 u_x u_y]   (eq. (20),
///     (27))
/// has the five combined coefficients x1…x5 of eq. (21)-(25). They are estimated by recursive least
/// squares in information form (the Kalman filter of a constant state). docs/errata.md#003-eq20:
/// the squared noise term of eq. (20) biases x1 by E|n|²/(2g²); the estimator removes it with the
/// noise variance measured from successive differences.
///
/// Attitude (eq. (28)-(38)): pitch and roll errors are a mean, an Earth-rate fundamental and a
/// second harmonic; their ten Fourier coefficients (mean, cos/sin of S, cos/sin of 2S) are fitted
/// by least squares.
///
/// Separation (eq. (39)-(41)): (ΔSF_x/2SF_x − ΔSF_y/2SF_y) from x4, δφ2s, δθ2c and (Δβ_yz −
/// Δβ_xz)/2 from x5, δφ2c, δθ2s (inverse-variance weighted, where the paper averages equally); the
/// six (∇x/g, ∇y/g, Δβyx, Δβzx, Δβxy, Δβzy) from x2, x3, δφ1s, δφ1c, δθ1c, δθ1s.
/// docs/errata.md#003-eq41: that system has rank 4 (f_z^p = g sin L is constant): ∇x/g and Δβxy are
/// determined only as ∇x/g − Δβxy sin L, ∇y/g and Δβyx only as ∇y/g + Δβyx sin L. The rank is
/// detected, not assumed.
///
/// Sign conventions (those that reproduce the printed equations; docs/errata.md#003-table4: Table
/// 4's reference values do not all follow from them): the platform-frame specific force is measured
/// as f̂ = (I + diag(ΔSF/SF) + ΔC_p^a) f − ∇ with ΔC_p^a of eq. (14).

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/gimbal_platform.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/series_file.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// Residual accelerometer errors after the device-level stages.
struct ResidualErrors {
  Vec3 scale = Vec3::Zero();     ///< ΔSF_i / SF_i (dimensionless)
  Vec3 bias_ms2 = Vec3::Zero();  ///< ∇_i [m/s²]
  /// Δβ of eq. (14) [rad]
  double beta_xz = 0, beta_yz = 0, beta_zy = 0, beta_xy = 0, beta_yx = 0, beta_zx = 0;
};
/// Paper 003 Tables 2 and 3.
ResidualErrors Wu2018Residuals();

/// Mean, fundamental (cos S, sin S) and second harmonic (cos 2S, sin 2S) of an attitude error.
struct FourierCoefficients {
  double mean = 0, c1 = 0, s1 = 0, c2 = 0, s2 = 0;
};

/// The 15 combined coefficients of eq. (21)-(25), (29)-(38) [rad], with the base tilt and gimbal
/// terms of eq. (29) and (34) set to zero.
struct CombinedCoefficients {
  Eigen::Matrix<double, 5, 1> x = Eigen::Matrix<double, 5, 1>::Zero();
  FourierCoefficients pitch, roll;
};
/// The printed equations evaluated (latitude in radians, g in m/s²).
CombinedCoefficients CombinedFromResiduals(const ResidualErrors& errors, double latitude_rad,
                                           double gravity_ms2);

struct SystemSimulationOptions {
  ResidualErrors errors = Wu2018Residuals();
  double latitude_deg = 40.0;
  double gravity_ms2 = 0;  ///< 0: WGS-84 normal gravity at the latitude
  double rate_hz = 100.0;
  double duration_s = 86400.0;
  double noise_ms2 = 5e-3;  ///< white noise per axis of the specific force
  /// White noise of each attitude error sample [rad]; negative: noise_ms2 / g (not given by the
  /// paper; an attitude error is about a specific-force error over g, eq. (28)).
  double attitude_noise_rad = -1.0;
  std::uint64_t seed = 1;
};
/// Calls `sink` with every sample in time order (deterministic in the seed); the attitude errors
/// follow the Fourier series of CombinedFromResiduals plus noise.
void SimulateSystemLevel(const SystemSimulationOptions& options,
                         const std::function<void(const SystemSample&)>& sink);

/// An estimated value with its 1σ.
struct Estimate {
  std::string name;
  double value = 0, std = 0;
};

/// Options of the system-level estimator. The estimate is a closed form (kClosedForm: normal
/// equations of linear least squares); the options state what the data must hold for it.
struct SystemLevelOptions {
  /// Latitude of the base [rad]: required; within (−89°, 89°) and at least 1° from the equator
  /// (where sin L vanishes and the attitude errors' second harmonics carry no information,
  /// eq. (32), (33)).
  double latitude_rad = std::nan("");
  double gravity_ms2 = 0;  ///< 0: WGS-84 normal gravity at the latitude
  long min_samples = 100;  ///< fewer: DataError from Finish()
  /// Platform angle S = ω_ie t the series must cover [rad] (1 rad is 3.8 h; 24 h recommended);
  /// less: DataError from Finish().
  double min_platform_angle_rad = 1.0;
  /// Eq. (41)'s whitened 6x6 system has rank r = #{σ_i > rank_tolerance · σ_1}.
  double rank_tolerance = 1e-9;
  /// Remove the noise term E|n|²/(2g²) from x1 (docs/errata.md#003-eq20).
  bool correct_x1_noise = true;
  /// An error message when an option is out of range, else std::nullopt.
  std::optional<std::string> Validate() const;
};

struct SystemLevelResult {
  long samples = 0;
  double gravity_ms2 = 0;  ///< the g used
  Eigen::Matrix<double, 5, 1> x = Eigen::Matrix<double, 5, 1>::Zero(), x_std = x;
  FourierCoefficients pitch, roll, pitch_std, roll_std;
  Vec3 noise_ms2 = Vec3::Zero();          ///< per-axis white noise from successive differences
  double x1_noise_correction = 0;         ///< E|n|²/(2g²) removed from x1
  int rank = 0;                           ///< of the eq. (41) system (6 unknowns)
  std::vector<Estimate> determined;       ///< parameters and combinations the data determine
  std::vector<std::string> undetermined;  ///< parameters they do not (never given a value)
  /// kClosedForm; the message states the solution's conditioning and the rank rule. The costs
  /// are those of the specific-force fit (eq. (27)): Σ z² and the residual sum of squares.
  PlatformSummary summary;
};

/// Accumulates samples (any order, constant memory) and solves. The constructor throws
/// std::invalid_argument for options that fail Validate(); Finish() throws DataError with fewer
/// than min_samples samples or less platform angle covered than min_platform_angle_rad.
class SystemLevelEstimator {
 public:
  explicit SystemLevelEstimator(const SystemLevelOptions& options);
  void Add(const SystemSample& sample);
  SystemLevelResult Finish() const;
  double gravity_ms2() const { return gravity_; }  ///< resolved from the options

 private:
  SystemLevelOptions options_;
  double latitude_, gravity_;
  Eigen::Matrix<double, 5, 5> gram_ = Eigen::Matrix<double, 5, 5>::Zero();  // Σ b bᵀ
  Eigen::Matrix<double, 5, 3> rhs_ = Eigen::Matrix<double, 5, 3>::Zero();   // Σ b (z, roll, pitch)
  Vec3 sum_squares_ = Vec3::Zero();  // Σ z², roll², pitch²
  Vec3 difference_squares_ = Vec3::Zero();
  Vec3 previous_f_ = Vec3::Zero();
  long count_ = 0;
  double s_min_ = 0, s_max_ = 0;
};

}  // namespace accelcal
