#include "accelcal/design.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "solvers/drift_fit.hpp"
#include "solvers/solver_common.hpp"
#include "solvers/thermal_fit.hpp"

namespace accelcal {

namespace {

using Rows12 = Eigen::Matrix<double, Eigen::Dynamic, kMaxParameters>;

// The frame of a device for an orientation-free design: a platform-frame (full) K has no gauge of
// its own (frame.hpp); its x-first form (ChangeFrame, linear model) is the same device.
Frame GravityOnlyFrame(const Mat33& K) {
  const Frame frame = FrameOf(K);
  if (frame == Frame::kPlatform) {
    throw std::invalid_argument(
        "the device's K is a full matrix (platform frame): give its x-first form (ChangeFrame)");
  }
  return frame;
}

// A planned experiment in the x-first gauge the solvers use: a z-first device is the x-first
// device of the mirrored problem (frame.hpp). Holds the (absent) readings its Problem refers to.
struct Plan {
  Plan(const ModelParameters& device_in, ModelKind model, double gravity,
       const std::vector<Vec3>& directions_in, const Vec3& sigma_raw)
      : frame(GravityOnlyFrame(device_in.K)),
        device(frame == Frame::kZFirst ? MirrorAxes(device_in) : device_in),
        directions(directions_in),
        sigma(frame == Frame::kZFirst ? Vec3(MirrorAxes(sigma_raw).cwiseAbs()) : sigma_raw),
        no_readings(directions_in.size()),
        problem{no_readings, gravity, model} {
    if (model == ModelKind::kLinear) device.k2.setZero();
    if (frame == Frame::kZFirst) {
      for (Vec3& c : directions) c = MirrorAxes(c);
    }
  }
  Plan(const Plan&) = delete;
  Plan& operator=(const Plan&) = delete;

  // The information rows u_k divided by the noise along each normal, so I = WᵀW (12-parameter
  // layout); A's diagonal for FinishInformation.
  Rows12 WhitenedRows(internal::Vec12* A_diagonal) const {
    const internal::InformationRows rows =
        internal::ReducedInformationRows(problem, device, directions);
    Rows12 W = rows.U;
    for (Eigen::Index k = 0; k < W.rows(); ++k) {
      W.row(k) /=
          std::sqrt(rows.normals[static_cast<std::size_t>(k)].cwiseAbs2().dot(sigma.cwiseAbs2()));
    }
    if (A_diagonal != nullptr) {
      // A's diagonal whitened as the rows are (axis i's regressors by its σ_i²), so that the
      // Jacobi-scaled information, and with it the observability test, does not depend on the
      // noise level: the free block against the fixed parameters' identity block.
      *A_diagonal = rows.A_diagonal;
      A_diagonal->segment<3>(internal::kGroupStart[0]) /= sigma(0) * sigma(0);
      A_diagonal->segment<4>(internal::kGroupStart[1]) /= sigma(1) * sigma(1);
      A_diagonal->segment<5>(internal::kGroupStart[2]) /= sigma(2) * sigma(2);
    }
    return W;
  }

  Frame frame;
  ModelParameters device;
  std::vector<Vec3> directions;
  Vec3 sigma;
  std::vector<Vec3> no_readings;
  internal::Problem problem;  // refers to no_readings
};

// Whitened rows on the model's active columns, in the parameter metric of TerminationType
// (relative change of the prediction): a scaling fixed by the device, so log det compares sets
// and does not depend on the parameters' units.
Eigen::MatrixXd ScaledActiveRows(const Plan& plan) {
  const Rows12 W = plan.WhitenedRows(nullptr);
  const internal::Vec12 metric = internal::ParameterScales(plan.problem, plan.device);
  const std::vector<int>& cols = ActiveColumns(plan.problem.model);
  Eigen::MatrixXd scaled(W.rows(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j) {
    scaled.col(static_cast<Eigen::Index>(j)) = W.col(cols[j]) / metric(cols[j]);
  }
  return scaled;
}

}  // namespace

double LogDetInformation(const ModelParameters& device, ModelKind model, double gravity,
                         const std::vector<Vec3>& directions, const Vec3& sigma_raw) {
  const Eigen::MatrixXd W = ScaledActiveRows(Plan(device, model, gravity, directions, sigma_raw));
  Eigen::LDLT<Eigen::MatrixXd> ldlt(W.transpose() * W);
  const Eigen::VectorXd d = ldlt.vectorD();
  if (ldlt.info() != Eigen::Success || !(d.minCoeff() > 0)) {
    return -std::numeric_limits<double>::infinity();
  }
  return d.array().log().sum();
}

namespace {

// What an exchange search did: swaps made, and whether it stopped at its sweep cap.
struct ExchangeReport {
  int exchanges = 0;
  bool capped = false;
};

enum class Criterion {
  kDeterminant,  ///< D-optimal: log det A
  kTrace,        ///< A-optimal: tr A⁻¹
};

// Fedorov exchange on the information A = Σ_chosen w_kᵀ w_k of the rows W: each sweep makes the
// one swap of a chosen i for an unchosen j that improves the criterion most, until none improves
// it by more than a relative 1e-10 or `max_sweeps` sweeps were made (report->capped). With d_k =
// w_k A⁻¹ w_kᵀ and d_ij = w_i A⁻¹ w_jᵀ, the swap multiplies det A by (1 + d_j)(1 − d_i) + d_ij²
// (the rank-2 determinant lemma); it lowers tr A⁻¹ by tr(M⁻¹N) (Woodbury, A' = A + U C Uᵀ with
// U = (w_jᵀ w_iᵀ), C = diag(1, −1), M = C⁻¹ + UᵀA⁻¹U, N = UᵀA⁻²U, det M = −ratio): a swap that
// would make A singular (ratio ≤ 1e-9) is skipped for the trace.
void FedorovExchange(const Eigen::MatrixXd& W, Criterion criterion, int max_sweeps,
                     std::vector<bool>* chosen_in, Eigen::MatrixXd* A_in, ExchangeReport* report) {
  std::vector<bool>& chosen = *chosen_in;
  Eigen::MatrixXd& A = *A_in;
  const auto n = static_cast<int>(W.rows());
  const auto P = static_cast<int>(W.cols());
  for (int sweep = 0;; ++sweep) {
    if (sweep == max_sweeps) {
      report->capped = true;
      return;
    }
    const Eigen::MatrixXd A_inv = A.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
    const Eigen::MatrixXd V = W * A_inv;  // rows w_k A⁻¹
    const Eigen::VectorXd d = (V.array() * W.array()).rowwise().sum();
    Eigen::VectorXd e;  // |w_k A⁻¹|², for the trace
    if (criterion == Criterion::kTrace) e = V.rowwise().squaredNorm();
    double best = criterion == Criterion::kDeterminant ? 1.0 + 1e-10 : 1e-10 * A_inv.trace();
    int best_in = -1, best_out = -1;
    for (int i = 0; i < n; ++i) {
      if (!chosen[static_cast<std::size_t>(i)]) continue;
      for (int j = 0; j < n; ++j) {
        if (chosen[static_cast<std::size_t>(j)]) continue;
        const double dij = V.row(i).dot(W.row(j));
        const double ratio = (1.0 + d(j)) * (1.0 - d(i)) + dij * dij;
        double gain = ratio;
        if (criterion == Criterion::kTrace) {
          if (!(ratio > 1e-9)) continue;
          const double eij = V.row(i).dot(V.row(j));
          // tr(M⁻¹N) with M = [[1 + d_j, d_ij], [d_ij, d_i − 1]], det M = −ratio.
          gain = ((d(i) - 1.0) * e(j) - 2.0 * dij * eij + (1.0 + d(j)) * e(i)) / -ratio;
        }
        if (gain > best) best = gain, best_in = i, best_out = j;
      }
    }
    if (best_in < 0) return;
    chosen[static_cast<std::size_t>(best_in)] = false;
    chosen[static_cast<std::size_t>(best_out)] = true;
    A +=
        W.row(best_out).transpose() * W.row(best_out) - W.row(best_in).transpose() * W.row(best_in);
    ++report->exchanges;
  }
}

std::vector<int> ChooseD(const ModelParameters& device, ModelKind model, double gravity,
                         const std::vector<Vec3>& candidates, const Vec3& sigma_raw, int count,
                         int max_sweeps, ExchangeReport* report) {
  const int n = static_cast<int>(candidates.size());
  const int P = NumParameters(model);
  if (count > n) throw std::invalid_argument("more positions asked for than there are candidates");
  if (count < MinimumPositions(model)) {
    throw std::invalid_argument("the " + std::string(ToString(model)) + " model needs at least " +
                                std::to_string(MinimumPositions(model)) + " positions");
  }
  // In the device's parameter metric (WhitenedRows): the argmax does not depend on a fixed
  // scaling, and it keeps the matrices well conditioned.
  const Eigen::MatrixXd W = ScaledActiveRows(Plan(device, model, gravity, candidates, sigma_raw));
  std::vector<bool> chosen(static_cast<std::size_t>(n), false);
  // Greedy: add the candidate with the largest w A⁻¹ wᵀ, A regularised while singular (relative to
  // one candidate's contribution, so the first picks see a well-conditioned A).
  const double regularisation = 1e-6 * W.colwise().squaredNorm().maxCoeff() / n;
  Eigen::MatrixXd A = regularisation * Eigen::MatrixXd::Identity(P, P);
  for (int step = 0; step < count; ++step) {
    const Eigen::MatrixXd A_inv = A.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
    int best = -1;
    double best_gain = -1;
    for (int j = 0; j < n; ++j) {
      if (chosen[static_cast<std::size_t>(j)]) continue;
      const double gain = W.row(j) * A_inv * W.row(j).transpose();
      if (gain > best_gain) best_gain = gain, best = j;
    }
    if (best < 0) throw std::invalid_argument("the candidates give no information (degenerate)");
    chosen[static_cast<std::size_t>(best)] = true;
    A += W.row(best).transpose() * W.row(best);
  }
  A -= regularisation * Eigen::MatrixXd::Identity(P, P);
  FedorovExchange(W, Criterion::kDeterminant, max_sweeps, &chosen, &A, report);
  std::vector<int> indices;
  for (int k = 0; k < n; ++k) {
    if (chosen[static_cast<std::size_t>(k)]) indices.push_back(k);
  }
  return indices;
}

}  // namespace

std::vector<int> ChooseDOptimal(const ModelParameters& device, ModelKind model, double gravity,
                                const std::vector<Vec3>& candidates, const Vec3& sigma_raw,
                                int count) {
  ExchangeReport report;
  return ChooseD(device, model, gravity, candidates, sigma_raw, count, 100, &report);
}

double TraceCrlb(const ModelParameters& device, ModelKind model, double gravity,
                 const std::vector<Vec3>& directions, const Vec3& sigma_raw) {
  const Eigen::MatrixXd W = ScaledActiveRows(Plan(device, model, gravity, directions, sigma_raw));
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(W.transpose() * W);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) {
    return std::numeric_limits<double>::infinity();
  }
  return ldlt.solve(Eigen::MatrixXd::Identity(W.cols(), W.cols())).trace();
}

namespace {

// Fedorov exchange on the trace of A⁻¹ from the chosen set `chosen`; the trace it reaches
// (infinite when the start is singular).
double ExchangeOnTrace(const Eigen::MatrixXd& W, std::vector<bool>* chosen_in, int max_sweeps,
                       ExchangeReport* report) {
  std::vector<bool>& chosen = *chosen_in;
  const auto n = static_cast<int>(W.rows());
  const auto P = static_cast<int>(W.cols());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(P, P);
  for (int k = 0; k < n; ++k) {
    if (chosen[static_cast<std::size_t>(k)]) A += W.row(k).transpose() * W.row(k);
  }
  Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) {
    return std::numeric_limits<double>::infinity();
  }
  FedorovExchange(W, Criterion::kTrace, max_sweeps, &chosen, &A, report);
  return A.ldlt().solve(Eigen::MatrixXd::Identity(P, P)).trace();
}

}  // namespace

namespace {

std::vector<int> ChooseA(const ModelParameters& device, ModelKind model, double gravity,
                         const std::vector<Vec3>& candidates, const Vec3& sigma_raw, int count,
                         int max_sweeps, ExchangeReport* report) {
  const std::vector<int> d_optimal =
      ChooseD(device, model, gravity, candidates, sigma_raw, count, max_sweeps, report);
  const auto n = candidates.size();
  const Eigen::MatrixXd W = ScaledActiveRows(Plan(device, model, gravity, candidates, sigma_raw));
  // The trace has more local minima under single exchanges than log det: besides the D-optimal
  // start, kRestarts random subsets (a fixed seed: deterministic), keeping the best.
  constexpr int kRestarts = 8;
  std::vector<bool> best(n, false);
  for (int k : d_optimal) best[static_cast<std::size_t>(k)] = true;
  double best_trace = ExchangeOnTrace(W, &best, 2 * max_sweeps, report);
  std::mt19937_64 random(12345);
  std::vector<std::size_t> order(n);
  for (int restart = 0; restart < kRestarts; ++restart) {
    std::iota(order.begin(), order.end(), 0);
    for (std::size_t i = n - 1; i > 0; --i) std::swap(order[i], order[random() % (i + 1)]);
    std::vector<bool> chosen(n, false);
    for (int k = 0; k < count; ++k) chosen[order[static_cast<std::size_t>(k)]] = true;
    const double trace = ExchangeOnTrace(W, &chosen, 2 * max_sweeps, report);
    if (trace < best_trace) best_trace = trace, best = chosen;
  }
  std::vector<int> indices;
  for (std::size_t k = 0; k < n; ++k) {
    if (best[k]) indices.push_back(static_cast<int>(k));
  }
  return indices;
}

}  // namespace

std::vector<int> ChooseAOptimal(const ModelParameters& device, ModelKind model, double gravity,
                                const std::vector<Vec3>& candidates, const Vec3& sigma_raw,
                                int count) {
  ExchangeReport report;
  return ChooseA(device, model, gravity, candidates, sigma_raw, count, 100, &report);
}

PlannedUncertainty PredictUncertainty(const ModelParameters& device, ModelKind model,
                                      double gravity, const std::vector<Vec3>& directions,
                                      const Vec3& sigma_raw) {
  if (!(gravity > 0) || !sigma_raw.allFinite() || !(sigma_raw.minCoeff() > 0)) {
    throw std::invalid_argument("the gravity and the noise must be positive");
  }
  for (const Vec3& c : directions) {
    if (!(std::abs(c.norm() - 1.0) < 1e-6)) {
      throw std::invalid_argument("planned directions must be unit vectors");
    }
  }
  const Plan plan(device, model, gravity, directions, sigma_raw);
  PlannedUncertainty out;
  out.model = model;
  out.frame = plan.frame;
  internal::Vec12 A_diagonal;
  const Rows12 W = plan.WhitenedRows(&A_diagonal);
  internal::Information info;
  info.reduced = W.transpose() * W;
  internal::FinishInformation(model, A_diagonal, &info);
  out.rcond = info.rcond;
  out.observable = info.rcond >= internal::kMinInformationRcond;
  if (info.weakest >= 0) {
    out.weakest = std::string(
        ParameterSlots(ModelKind::kQuadratic, out.frame)[static_cast<std::size_t>(info.weakest)]
            .name);
  }
  out.std.K.setZero();
  if (!out.observable) return out;
  const internal::Mat12 inverse = info.Inverse();
  const std::vector<int>& cols = ActiveColumns(model);
  const int P = NumParameters(model);
  out.crlb.resize(P, P);
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) out.crlb(i, j) = inverse(cols[i], cols[j]);
  }
  if (plan.frame == Frame::kZFirst) {
    const Eigen::VectorXd d = MirrorSigns(model);
    out.crlb = d.asDiagonal() * out.crlb * d.asDiagonal();
  }
  out.std = Unpack(out.crlb.diagonal().cwiseMax(0.0).cwiseSqrt(), ParameterSlots(model, out.frame));
  return out;
}

PlannedDriftCost PredictDriftCost(const ModelParameters& device, ModelKind model, double gravity,
                                  const std::vector<Vec3>& directions, const Vec3& sigma_raw,
                                  const BiasModel& bias_model) {
  if (bias_model.constant()) throw std::invalid_argument("a constant bias does not drift");
  const PlannedUncertainty constant =
      PredictUncertainty(device, model, gravity, directions, sigma_raw);
  const Plan plan(device, model, gravity, directions, sigma_raw);
  std::vector<double> times;  // one position a minute
  for (std::size_t k = 0; k < directions.size(); ++k) times.push_back(60.0 * double(k));
  PlannedDriftCost out;
  out.bias_model = bias_model;
  const BiasTimeBasis basis = BiasTimeBasis::For(bias_model, times);
  const internal::DriftProblem lsq(plan.problem, basis, times);
  const int P = NumParameters(model), J = basis.size(), n = P + 3 * J;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  x.head(P) = Pack(plan.device, model);
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t k = 0; k < directions.size(); ++k) {
    Vec3 normal;
    const Eigen::VectorXd u =
        internal::InformationRow(lsq, x, static_cast<int>(k), plan.directions[k], &normal);
    information += u * u.transpose() / normal.cwiseAbs2().dot(plan.sigma.cwiseAbs2());
  }
  // Jacobi-scaled, as the observability test of calibrate.
  const Eigen::VectorXd scale = information.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * information * scale.asDiagonal();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(scaled);
  const Eigen::VectorXd d = ldlt.vectorD();
  out.observable = constant.observable && ldlt.info() == Eigen::Success &&
                   d.minCoeff() > internal::kMinInformationRcond * d.maxCoeff();
  if (!out.observable) return out;
  const Eigen::MatrixXd crlb =
      scale.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(n, n)) * scale.asDiagonal();
  out.inflation.resize(P);
  for (int i = 0; i < P; ++i) {
    // Slot i of the mirrored x-first problem is slot i of the device's frame (frame.hpp).
    out.inflation(i) = std::sqrt(crlb(i, i) / constant.crlb(i, i));
    if (out.worst < 0 || out.inflation(i) > out.inflation(out.worst)) out.worst = i;
  }
  BiasDrift planned;  // the drift's CRLB, in the device's frame
  planned.basis = basis;
  planned.D = Eigen::MatrixXd::Zero(3, J);
  planned.covariance = crlb;
  if (plan.frame == Frame::kZFirst) planned = MirrorAxes(planned, model);
  out.drift_sigma.resize(3, J);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < J; ++j) {
      out.drift_sigma(i, j) = std::sqrt(planned.covariance(P + i * J + j, P + i * J + j));
    }
  }
  return out;
}

PlannedThermal PredictThermalUncertainty(const ModelParameters& device, ModelKind model,
                                         double gravity, const std::vector<Vec3>& directions,
                                         const std::vector<double>& temperatures_c,
                                         const Vec3& sigma_raw, const ThermalDegrees& degrees) {
  if (temperatures_c.empty()) throw std::invalid_argument("a schedule needs a temperature");
  double sum = 0;
  for (double t : temperatures_c) {
    if (!std::isfinite(t)) throw std::invalid_argument("temperatures must be finite");
    sum += t;
  }
  PlannedThermal out;
  out.degrees = degrees;
  out.t_ref_c = sum / static_cast<double>(temperatures_c.size());
  std::vector<double> sorted = temperatures_c;
  std::sort(sorted.begin(), sorted.end());
  int distinct = 1;
  for (std::size_t i = 1, first = 0; i < sorted.size(); ++i) {
    if (sorted[i] - sorted[first] >= kMinThermalSeparation_K) ++distinct, first = i;
  }
  if (distinct < degrees.Max() + 1) {
    (void)ThermalSlots(model, degrees);  // degrees the model cannot take still throw
    return out;
  }
  // The device and its directions in the x-first frame the thermal model is written in.
  const FrameChange change = ChangeFrame(device.K, Frame::kXFirst);
  ModelParameters x_first = device;
  x_first.K = change.K;
  const ThermalParameters thermal = ConstantOverTemperature(x_first, model, degrees, out.t_ref_c);
  std::vector<Vec3> dirs;
  std::vector<double> temps;
  for (double t : temperatures_c) {
    for (const Vec3& c : directions) {
      dirs.push_back(Vec3(change.Q_old_new.transpose() * c.normalized()));
      temps.push_back(t);
    }
  }
  const std::vector<Vec3> no_readings(dirs.size());
  const internal::Problem problem{no_readings, gravity, model};
  const internal::ThermalProblem lsq(problem, degrees, out.t_ref_c, temps);
  const Eigen::VectorXd x = Pack(thermal, model);
  const auto n = x.size();
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    Vec3 normal;
    const Eigen::VectorXd u =
        internal::InformationRow(lsq, x, static_cast<int>(k), dirs[k], &normal);
    information += u * u.transpose() / normal.cwiseAbs2().dot(sigma_raw.cwiseAbs2());
  }
  // Jacobi-scaled, as the observability test of calibrate.
  const Eigen::VectorXd scale = information.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(scale.asDiagonal() * information * scale.asDiagonal());
  const Eigen::VectorXd d = ldlt.vectorD();
  out.observable =
      ldlt.info() == Eigen::Success && d.minCoeff() > internal::kMinInformationRcond * d.maxCoeff();
  if (!out.observable) return out;
  out.crlb = scale.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(n, n)) * scale.asDiagonal();
  out.sigma = out.crlb.diagonal().cwiseMax(0.0).cwiseSqrt();
  return out;
}

std::optional<std::vector<Vec3>> SchemeDirections(std::string_view name) {
  if (name == "yang18") return Yang18Directions();
  if (name == "six") {
    return std::vector<Vec3>{Vec3::UnitX(),  -Vec3::UnitX(), Vec3::UnitY(),
                             -Vec3::UnitY(), Vec3::UnitZ(),  -Vec3::UnitZ()};
  }
  constexpr std::string_view kRandom = "random:";
  if (name.substr(0, kRandom.size()) != kRandom) return std::nullopt;
  // A "random:" name is a scheme, never a file: a bad count is an error, not a missing file.
  const auto bad = [&] {
    return InputError(std::string(name), 0,
                      "random:N[:SEED] takes a whole number of positions N from 1 to " +
                          std::to_string(kMaxRandomPositions) + " and a whole-number seed");
  };
  std::string_view rest = name.substr(kRandom.size());
  const std::size_t colon = rest.find(':');
  int count = 0;
  std::uint64_t seed = 1;
  const std::string_view count_text = rest.substr(0, colon);
  auto [end, ec] = std::from_chars(count_text.data(), count_text.data() + count_text.size(), count);
  if (ec != std::errc() || end != count_text.data() + count_text.size() || count < 1 ||
      count > kMaxRandomPositions) {
    throw bad();
  }
  if (colon != std::string_view::npos) {
    const std::string_view seed_text = rest.substr(colon + 1);
    auto [e2, ec2] = std::from_chars(seed_text.data(), seed_text.data() + seed_text.size(), seed);
    if (ec2 != std::errc() || e2 != seed_text.data() + seed_text.size()) throw bad();
  }
  return RandomDirections(count, seed);
}

std::string_view ToString(DesignCriterion criterion) { return NameOf(criterion); }

std::optional<std::string> DesignOptions::Validate() const {
  if (!(gravity > 0) || !std::isfinite(gravity)) return "gravity must be positive and finite";
  if (!sigma_raw.allFinite() || !(sigma_raw.minCoeff() > 0)) {
    return "sigma_raw must be positive and finite on every axis";
  }
  if (!device.K.allFinite() || !device.bias.allFinite() || !device.k2.allFinite()) {
    return "the device's parameters must be finite";
  }
  if (choose < 0) return "choose must be 0 (no choice) or a number of positions";
  if (max_exchanges < 1) return "max_exchanges must be at least 1";
  if (frame == Frame::kPlatform && model != ModelKind::kLinear) {
    return "a quadratic platform-frame device has no orientation-free equivalent (the squared "
           "terms act on platform axes): the model must be linear";
  }
  return std::nullopt;
}

DesignResult Design(const std::vector<Vec3>& directions_in, const DesignOptions& options) {
  if (auto why = options.Validate()) throw OptionError(*why);
  // A platform-frame device (known-orientation fit) has a full K: the orientation-free bound is
  // that of the same linear device in its x-first form (frame.hpp), the directions rotated with it.
  ModelParameters device = options.device;
  std::vector<Vec3> directions = directions_in;
  if (options.frame == Frame::kPlatform) {
    const FrameChange change = ChangeFrame(device.K, Frame::kXFirst);
    device.K = change.K;
    device.k2.setZero();
    for (Vec3& c : directions) c = change.Q_old_new.transpose() * c;
  }
  const ModelKind model = options.model;
  const double g = options.gravity;
  const Vec3& sigma = options.sigma_raw;
  DesignResult out;
  if (options.choose > 0) {
    ExchangeReport report;
    out.chosen = options.criterion == DesignCriterion::kD
                     ? ChooseD(device, model, g, directions, sigma, options.choose,
                               options.max_exchanges, &report)
                     : ChooseA(device, model, g, directions, sigma, options.choose,
                               options.max_exchanges, &report);
    std::vector<Vec3> subset;
    for (int k : out.chosen) subset.push_back(directions[static_cast<std::size_t>(k)]);
    const std::vector<Vec3> yang18 = Yang18Directions();
    out.d_efficiency = std::exp((LogDetInformation(device, model, g, subset, sigma) -
                                 LogDetInformation(device, model, g, yang18, sigma)) /
                                NumParameters(model));
    out.a_efficiency =
        TraceCrlb(device, model, g, yang18, sigma) / TraceCrlb(device, model, g, subset, sigma);
    out.summary.exchanges = report.exchanges;
    out.summary.converged = !report.capped;
    out.summary.termination_message =
        report.capped
            ? "reached max_exchanges = " + std::to_string(options.max_exchanges) +
                  " sweeps with swaps still improving the criterion"
            : std::string(options.criterion == DesignCriterion::kD
                              ? "no swap of a chosen and an unchosen position raises det I by "
                                "more than 1e-10 relative"
                              : "no swap of a chosen and an unchosen position lowers tr CRLB by "
                                "more than 1e-10 relative");
    directions = std::move(subset);
  } else {
    out.chosen.resize(directions.size());
    std::iota(out.chosen.begin(), out.chosen.end(), 0);
    out.summary.termination_message = "no choice: every position evaluated";
  }
  out.planned = PredictUncertainty(device, model, g, directions, sigma);
  return out;
}

}  // namespace accelcal
