// The IEEE noise terms fitted to an Allan variance (noise_model.hpp).
#include "accelcal/noise_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include <Eigen/Dense>

#include "statistics/student_t.hpp"

namespace accelcal {

namespace {

constexpr double kLn2 = 0.69314718055994530942;
constexpr double kPi = 3.14159265358979323846;

// g_t(τ): σ²(τ) = Σ_t c_t g_t(τ) (IEEE Std 952-1997, Table C.2).
std::array<double, kNoiseTerms> Basis(double tau) {
  return {3 / (tau * tau), 1 / tau, 2 * kLn2 / kPi, tau / 3, tau * tau / 2};
}

std::size_t Index(NoiseTerm t) { return static_cast<std::size_t>(t); }

PowerLawNoise NoiseOf(int term) {
  switch (static_cast<NoiseTerm>(term)) {
    case NoiseTerm::kQuantization:
      return PowerLawNoise::kQuantization;
    case NoiseTerm::kWhite:
      return PowerLawNoise::kWhite;
    case NoiseTerm::kBiasInstability:
      return PowerLawNoise::kFlicker;
    case NoiseTerm::kRandomWalk:
    case NoiseTerm::kRateRamp:  // deterministic: its estimate scatters by the noise under it
      return PowerLawNoise::kRandomWalk;
  }
  return PowerLawNoise::kWhite;
}

// The correlation of the estimates (AllanCorrelation), for one set of points and any terms:
// I_ij = ∫ A_i A_j S² dν over ln ν, 64 points an octave from ½ down to 10⁻³/m_max (8 a period
// of sin⁴ where it turns fastest; 256 changed no correlation by more than 4e-5, on 11 and 19
// octaves of each term and a mix). Where sin⁴(π ν m) turns faster than that (ν m ≥ 16) it is
// replaced by its mean over a period, 3/8; for two such octaves k apart the product's mean over
// the slower one's period is 35/128 (k = 0), 7/64 (k = 1), 9/64 = (3/8)² (k ≥ 2 or not a power
// of two apart). So I = Aᵀ diag(w) A, with a_i = sin⁴(π ν m_i) / (m_i² sin² π ν) or
// (3/8) / (m_i² sin² π ν), plus the corrections of k = 0 and 1 where both are fast; A is the
// same for every S. S = Σ_t c_t s_t(ν) over the four spectral terms (the rate ramp is not a
// spectrum), so S² and I are quadratic in c: I = Σ_{t,u} c_t c_u I_tu, the ten I_tu computed
// once, and each S after costs ten n × n sums (the fit's intervals ask for thousands).
class EstimateCorrelation {
 public:
  static constexpr int kSpectral = 4;  // Q, N, B, K

  explicit EstimateCorrelation(const std::vector<AllanPoint>& points) {
    const std::size_t n = points.size();
    const double tau0 = points.front().tau_s / static_cast<double>(points.front().m);
    double m_max = 1;
    std::vector<double> m;
    for (const AllanPoint& p : points) {
      m.push_back(static_cast<double>(p.m));
      m_max = std::max(m_max, static_cast<double>(p.m));
    }
    constexpr int kPerOctave = 64;
    const double step = std::log(2.0) / kPerOctave;
    const auto count = static_cast<Eigen::Index>(std::ceil(std::log(0.5 / (1e-3 / m_max)) / step));
    Eigen::MatrixXd A(count, static_cast<Eigen::Index>(n));
    // s_t(ν) of each spectral term at c_t = 1: 2πf c τ₀ (quantisation), 1, 1/2πf, 1/(2πf)².
    Eigen::MatrixXd spectra(count, kSpectral);
    std::vector<double> s2(static_cast<std::size_t>(count)), weight(s2.size());
    std::vector<std::size_t> fast_until(n, 0);  // per point: grid indices below are fast
    // sin(π ν m) for m = 2^k is sin(π ν') at the grid point k octaves up (ν' = ν 2^k): one table
    // of sin(π ν_h) for h from 5 octaves above ½ (ν m < 16 where it is needed) serves every
    // point of a power-of-two m, instead of a sine per point and row.
    constexpr long kAbove = 5 * kPerOctave + 1;
    const auto nu_at = [&](long h) {
      return 0.5 * std::exp(-step * (static_cast<double>(h) + 0.5));
    };
    std::vector<double> sines(static_cast<std::size_t>(count) + kAbove);
    for (long h = -kAbove; h < static_cast<long>(count); ++h) {
      sines[static_cast<std::size_t>(h + kAbove)] = std::sin(kPi * nu_at(h));
    }
    std::vector<long> octave(n, -1);  // log2 m, −1 where m is not a power of two
    for (std::size_t i = 0; i < n; ++i) {
      const auto whole = static_cast<std::uint64_t>(m[i]);
      if ((whole & (whole - 1)) == 0) {
        long k = 0;
        while ((std::uint64_t{1} << k) < whole) ++k;
        octave[i] = k;
      }
    }
    for (Eigen::Index g = 0; g < count; ++g) {
      const double nu = nu_at(static_cast<long>(g));
      const double sin2 =
          sines[static_cast<std::size_t>(g + kAbove)] * sines[static_cast<std::size_t>(g + kAbove)];
      s2[static_cast<std::size_t>(g)] = sin2;
      weight[static_cast<std::size_t>(g)] = nu * step;  // dν = ν d(ln ν)
      const double two_pi_f = 2 * kPi * nu / tau0;
      spectra(g, 0) = two_pi_f * two_pi_f * tau0;
      spectra(g, 1) = 1;
      spectra(g, 2) = 1 / two_pi_f;
      spectra(g, 3) = 1 / (two_pi_f * two_pi_f);
      for (std::size_t i = 0; i < n; ++i) {
        const bool fast = nu * m[i] >= 16;
        if (fast) fast_until[i] = static_cast<std::size_t>(g) + 1;      // ν falls with g
        const long up = static_cast<long>(g) - kPerOctave * octave[i];  // ν' = ν m's grid index
        const double sine = fast ? 0.0
                            : octave[i] >= 0 && up >= -kAbove
                                ? sines[static_cast<std::size_t>(up + kAbove)]
                                : std::sin(kPi * nu * m[i]);
        const double s4 = fast ? 0.375 : (sine * sine) * (sine * sine);
        A(g, static_cast<Eigen::Index>(i)) = s4 / (m[i] * m[i] * sin2);
      }
    }
    m_ = std::move(m);
    A_ = std::move(A);
    spectra_ = std::move(spectra);
    s2_ = std::move(s2);
    weight_ = std::move(weight);
    fast_until_ = std::move(fast_until);
    products_.resize(kSpectral * (kSpectral + 1) / 2);
  }

  Eigen::MatrixXd operator()(const std::array<double, kNoiseTerms>& c) const {
    const auto n = static_cast<Eigen::Index>(m_.size());
    Eigen::MatrixXd I = Eigen::MatrixXd::Zero(n, n);
    std::size_t k = 0;
    for (int t = 0; t < kSpectral; ++t) {
      for (int u = t; u < kSpectral; ++u, ++k) {
        const double cc = c[static_cast<std::size_t>(t)] * c[static_cast<std::size_t>(u)];
        if (cc != 0) I += cc * Product(t, u, k);
      }
    }
    Eigen::MatrixXd rho(I.rows(), I.cols());
    for (Eigen::Index i = 0; i < I.rows(); ++i) {
      for (Eigen::Index j = 0; j < I.cols(); ++j) {
        rho(i, j) = i == j ? 1.0 : I(i, j) / std::sqrt(I(i, i) * I(j, j));
      }
    }
    return rho;
  }

 private:
  // I_tu (the k-th of the pairs t ≤ u, row by row), made when a fit first weighs by it: a term
  // whose estimate stays at or below 0 never needs its four.
  const Eigen::MatrixXd& Product(int t, int u, std::size_t k) const {
    std::optional<Eigen::MatrixXd>& product = products_[k];
    if (product) return *product;
    const std::size_t n = m_.size();
    const Eigen::Index count = A_.rows();
    const std::vector<double>& m = m_;
    Eigen::VectorXd w(count);
    // The corrections where both points are fast run over the grid's first min(fast_until) rows:
    // a running sum of w / sin⁴ π ν makes each one a lookup.
    std::vector<double> running(static_cast<std::size_t>(count) + 1);
    running[0] = 0;
    for (Eigen::Index g = 0; g < count; ++g) {
      const auto gi = static_cast<std::size_t>(g);
      w(g) = (t == u ? 1.0 : 2.0) * spectra_(g, t) * spectra_(g, u) * weight_[gi];
      running[gi + 1] = running[gi] + w(g) / (s2_[gi] * s2_[gi]);
    }
    Eigen::MatrixXd I = A_.transpose() * w.asDiagonal() * A_;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i; j < n; ++j) {
        const double ratio = std::log2(m[j] / m[i]);
        const long apart = std::lround(std::abs(ratio));
        if (apart > 1 || std::abs(std::abs(ratio) - static_cast<double>(apart)) > 1e-9) {
          continue;
        }
        const double excess = apart == 0 ? 35.0 / 128 - 9.0 / 64 : 7.0 / 64 - 9.0 / 64;
        const double sum = excess * running[std::min(fast_until_[i], fast_until_[j])] /
                           (m[i] * m[i] * m[j] * m[j]);
        I(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) += sum;
        if (i != j) I(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) += sum;
      }
    }
    product = std::move(I);
    return *product;
  }

  std::vector<double> m_;                // the points' m
  Eigen::MatrixXd A_, spectra_;          // a_i on the grid; s_t(ν) of the spectral terms
  std::vector<double> s2_, weight_;      // sin² π ν; ν dln ν
  std::vector<std::size_t> fast_until_;  // per point: grid indices below are fast
  mutable std::vector<std::optional<Eigen::MatrixXd>> products_;
};

// The correlation's products depend on the points' m and τ₀ alone, which the axes of one log
// share: the last one made is kept (per thread) and made again only for other m or τ₀. Shared, so
// that a fit holding one keeps it whatever a later fit of this thread asks for.
std::shared_ptr<const EstimateCorrelation> CorrelationFor(const std::vector<AllanPoint>& points) {
  struct Cached {
    double tau0 = 0;
    std::vector<std::uint64_t> m;
    std::shared_ptr<const EstimateCorrelation> correlation;
  };
  thread_local Cached cached;
  const double tau0 = points.front().tau_s / static_cast<double>(points.front().m);
  bool same = cached.correlation && cached.tau0 == tau0 && cached.m.size() == points.size();
  for (std::size_t i = 0; same && i < points.size(); ++i) same = cached.m[i] == points[i].m;
  if (!same) {
    cached.correlation = std::make_shared<const EstimateCorrelation>(points);
    cached.tau0 = tau0;
    cached.m.clear();
    for (const AllanPoint& p : points) cached.m.push_back(p.m);
  }
  return cached.correlation;
}

}  // namespace

const char* ToString(NoiseTerm term) {
  switch (term) {
    case NoiseTerm::kQuantization:
      return "quantization";
    case NoiseTerm::kWhite:
      return "white";
    case NoiseTerm::kBiasInstability:
      return "bias_instability";
    case NoiseTerm::kRandomWalk:
      return "random_walk";
    case NoiseTerm::kRateRamp:
      return "rate_ramp";
  }
  return "?";
}

Eigen::MatrixXd AllanCorrelation(const std::vector<AllanPoint>& points,
                                 const std::array<double, kNoiseTerms>& squared) {
  if (points.empty() || points.front().m == 0) {
    throw std::invalid_argument("AllanCorrelation: no points");
  }
  return EstimateCorrelation(points)(squared);
}

double NoiseModelAvar(const std::array<double, kNoiseTerms>& squared, double tau_s) {
  const std::array<double, kNoiseTerms> g = Basis(tau_s);
  double sum = 0;
  for (std::size_t t = 0; t < g.size(); ++t) sum += squared[t] * g[t];
  return sum;
}

namespace {

// The fit of points whose σ² are near 1 (FitNoiseModel scales them there).
// A term's upper bound from the Allan deviation alone: for a term the fit puts below 0 beyond its
// interval (then the terms do not describe the noise, and c + z σ_c, below 0 too, bounds
// nothing), and as the ceiling of the others' upper ends. Every term adds a variance ≥ 0, so c_j
// f_j(τ) ≤ σ²(τ) at every τ (f_j the term's avar at c_j = 1), and c_j is at most the least over τ
// of σ²(τ)'s upper confidence limit over f_j(τ); each limit at 1 − (1 − confidence)/n, so that all
// n hold together (Bonferroni). Each point's σ²(τ) upper limit at 1 − (1 − confidence)/n (0 where
// σ̂² is 0), for every term.
std::vector<double> EnvelopeLimits(const NoiseModelFit& fit, double confidence) {
  const std::size_t n = fit.points.size();
  const double each = 1 - (1 - confidence) / static_cast<double>(n);
  std::vector<double> limits(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(fit.points[i].avar > 0)) continue;
    const double high = AllanDeviationInterval(fit.points[i].avar, fit.edf[i], each).high;
    limits[i] = high * high;
  }
  return limits;
}

double EnvelopeBound(const NoiseModelFit& fit, const std::vector<double>& limits,
                     std::size_t term) {
  std::array<double, kNoiseTerms> unit{};
  unit[term] = 1;
  double bound = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const double f = NoiseModelAvar(unit, fit.points[i].tau_s);
    if (!(f > 0) || !(limits[i] > 0)) continue;
    bound = std::min(bound, limits[i] / f);
  }
  return std::isfinite(bound) ? std::sqrt(bound) : 0.0;
}

// The terms to fit, in NoiseTerm order, the points and the options checked.
std::vector<int> FittedTerms(const std::vector<AllanPoint>& points,
                             const NoiseFitOptions& options) {
  if (!(options.confidence > 0 && options.confidence < 1) || options.max_iterations < 1) {
    throw std::invalid_argument(
        "FitNoiseModel: the confidence must lie in (0, 1) and the iterations be at least 1");
  }
  std::vector<int> fitted;
  for (int t = 0; t < kNoiseTerms; ++t) {
    if (options.terms[static_cast<std::size_t>(t)]) fitted.push_back(t);
  }
  if (fitted.empty()) throw std::invalid_argument("FitNoiseModel: no term to fit");
  if (points.size() < fitted.size() + 1) {
    throw std::invalid_argument("FitNoiseModel: " + std::to_string(points.size()) +
                                " averaging times for " + std::to_string(fitted.size()) +
                                " terms: at least one more than the terms is needed");
  }
  for (const AllanPoint& p : points) {
    if (!(p.avar >= 0) || !std::isfinite(p.avar) || !(p.tau_s > 0) || p.m == 0) {
      throw std::invalid_argument(
          "FitNoiseModel: an Allan variance that is negative or not finite");
    }
  }
  return fitted;
}

// The least squares of a fit of points whose σ² are near 1: the fitted terms' columns G of each
// point's σ² (Gs scaled to unit norm: τ⁻² to τ² span many decades), the points' σ² a, and the
// correlation of their estimates.
struct NoiseProblem {
  NoiseProblem(const std::vector<AllanPoint>& in, const NoiseFitOptions& options)
      : points(in), fitted(FittedTerms(in, options)), correlation(CorrelationFor(in)) {
    const std::size_t n = points.size();
    const auto rows = static_cast<Eigen::Index>(n);
    const auto p = static_cast<Eigen::Index>(fitted.size());
    G.resize(rows, p);
    a.resize(rows);
    for (std::size_t i = 0; i < n; ++i) {
      const std::array<double, kNoiseTerms> g = Basis(points[i].tau_s);
      for (Eigen::Index j = 0; j < p; ++j) {
        G(static_cast<Eigen::Index>(i), j) =
            g[static_cast<std::size_t>(fitted[static_cast<std::size_t>(j)])];
      }
      a(static_cast<Eigen::Index>(i)) = points[i].avar;
    }
    scale = G.colwise().norm().transpose();
    Gs = G * scale.cwiseInverse().asDiagonal();
  }

  // The points' covariance Σ = D ρ D were the terms' squares `hypothesis` (each ≥ 0): D each
  // point's σ², split by term, times √(2/edf) of each; ρ the correlation of that spectrum.
  Eigen::MatrixXd SigmaOf(const std::array<double, kNoiseTerms>& hypothesis) const {
    const std::size_t n = points.size();
    const auto rows = static_cast<Eigen::Index>(n);
    Eigen::VectorXd sd(rows);
    for (std::size_t i = 0; i < n; ++i) {
      const std::array<double, kNoiseTerms> g = Basis(points[i].tau_s);
      double sum = 0;
      for (int t = 0; t < kNoiseTerms; ++t) {
        const double part =
            hypothesis[static_cast<std::size_t>(t)] * g[static_cast<std::size_t>(t)];
        if (part > 0) sum += part * std::sqrt(2 / AllanEdf(NoiseOf(t), points[i]));
      }
      sd(static_cast<Eigen::Index>(i)) = std::max(sum, 1e-300);
    }
    Eigen::MatrixXd sigma = sd.asDiagonal() * (*correlation)(hypothesis)*sd.asDiagonal();
    sigma.diagonal() *= 1 + 1e-9;
    return sigma;
  }

  // The term j's variance (scaled) were it c' (unscaled), the other terms fitted again with it
  // held there (their weights and correlation following them as in the fit).
  // `hypothesis` holds where the others start and is left where they ended (the next c' of a
  // search starts there: a few rounds instead of tens).
  double ProfileVariance(Eigen::Index j, double c_prime,
                         std::array<double, kNoiseTerms>& hypothesis, int max_iterations) const {
    const auto rows = static_cast<Eigen::Index>(points.size());
    const auto p = static_cast<Eigen::Index>(fitted.size());
    const auto term = static_cast<std::size_t>(fitted[static_cast<std::size_t>(j)]);
    hypothesis[term] = c_prime;
    if (p > 1) {
      Eigen::MatrixXd others(rows, p - 1);
      for (Eigen::Index k = 0, o = 0; k < p; ++k) {
        if (k != j) others.col(o++) = Gs.col(k);
      }
      const Eigen::VectorXd rest = a - G.col(j) * c_prime;
      Eigen::VectorXd x, x_before;
      for (int round = 1; round <= max_iterations; ++round) {
        const Eigen::LLT<Eigen::MatrixXd> llt(SigmaOf(hypothesis));
        const Eigen::MatrixXd A = llt.matrixL().solve(others);
        x_before = x;
        x = A.colPivHouseholderQr().solve(llt.matrixL().solve(rest));
        for (Eigen::Index k = 0, o = 0; k < p; ++k) {
          if (k == j) continue;
          const auto t = static_cast<std::size_t>(fitted[static_cast<std::size_t>(k)]);
          const double value = std::max(0.0, x(o++) / scale(k));
          hypothesis[t] = round == 1 ? value : 0.5 * (hypothesis[t] + value);
        }
        if (round == 1) continue;
        const Eigen::VectorXd spread = (A.transpose() * A).inverse().diagonal().cwiseSqrt();
        if (((x - x_before).cwiseAbs().array() <= 1e-3 * spread.array()).all()) break;
      }
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(SigmaOf(hypothesis));
    const Eigen::MatrixXd A = llt.matrixL().solve(Gs);
    return Eigen::MatrixXd((A.transpose() * A).inverse())(j, j);
  }

  const std::vector<AllanPoint>& points;
  const std::vector<int> fitted;  // the terms fitted, in NoiseTerm order
  Eigen::MatrixXd G, Gs;
  Eigen::VectorXd a, scale;
  const std::shared_ptr<const EstimateCorrelation> correlation;
};

// The weighted least squares, its weights (each point's σ and the correlation) iterated from the
// model's terms: the terms' scaled estimates and covariance, and the fit's χ².
struct WeightedFit {
  Eigen::VectorXd c_scaled;
  Eigen::MatrixXd covariance_scaled;
  double chi2 = 0;
};
WeightedFit IterateWeights(const NoiseProblem& problem, const NoiseFitOptions& options,
                           NoiseModelFit* fit) {
  const std::vector<AllanPoint>& points = problem.points;
  const std::vector<int>& fitted = problem.fitted;
  const Eigen::VectorXd& scale = problem.scale;
  const std::size_t n = points.size();
  const auto rows = static_cast<Eigen::Index>(n);
  const auto p = static_cast<Eigen::Index>(fitted.size());
  NoiseModelFit& out = *fit;
  WeightedFit w;
  Eigen::VectorXd& c_scaled = w.c_scaled;
  Eigen::MatrixXd& covariance_scaled = w.covariance_scaled;
  double& chi2 = w.chi2;
  // The first weights from the estimates themselves, independent; then the model's.
  // Each point's σ² by term (the model's positive part); first the estimate itself, as white.
  std::vector<std::array<double, kNoiseTerms>> parts(n);
  for (std::size_t i = 0; i < n; ++i) {
    parts[i] = {};
    parts[i][Index(NoiseTerm::kWhite)] = std::max(points[i].avar, 1e-300);
  }
  Eigen::MatrixXd rho = Eigen::MatrixXd::Identity(rows, rows);
  c_scaled = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd previous;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    // Σ = D ρ D, D each point's σ, √(2/edf) of its σ² (the model's, or the estimate's first).
    // Σ = D ρ D. D: each point's σ, Σ_t σ²_t √(2/edf_t) over the terms' parts of its σ² — exact
    // when one term dominates or all are of one kind, and smooth between (a point's weight does
    // not jump when the dominant term changes, which made the iteration cycle).
    Eigen::VectorXd sd(rows);
    for (std::size_t i = 0; i < n; ++i) {
      double sum = 0, total = 0;
      for (int t = 0; t < kNoiseTerms; ++t) {
        const double part = parts[i][static_cast<std::size_t>(t)];
        if (part > 0) sum += part * std::sqrt(2 / AllanEdf(NoiseOf(t), points[i]));
        total += part;
      }
      sd(static_cast<Eigen::Index>(i)) = sum;
      out.edf[i] = 2 * total * total / (sum * sum);
    }
    Eigen::MatrixXd sigma = sd.asDiagonal() * rho * sd.asDiagonal();
    // Octaves next to each other can correlate nearly to 1 under a steep spectrum: a ridge of
    // 1e-9 of the diagonal keeps the factor defined without changing the weights of note.
    sigma.diagonal() *= 1 + 1e-9;
    const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
    const Eigen::MatrixXd A = llt.matrixL().solve(problem.Gs);
    const Eigen::VectorXd b = llt.matrixL().solve(problem.a);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    if (qr.rank() < p) {
      throw std::invalid_argument(
          "FitNoiseModel: the averaging times do not tell the terms apart (too few octaves for "
          "them)");
    }
    previous = c_scaled;
    c_scaled = qr.solve(b);
    covariance_scaled = (A.transpose() * A).inverse();
    chi2 = (A * c_scaled - b).squaredNorm();
    // The terms unconstrained; the weights and correlation from their positive part.
    std::array<double, kNoiseTerms> positive{};
    for (Eigen::Index j = 0; j < p; ++j) {
      positive[static_cast<std::size_t>(fitted[static_cast<std::size_t>(j)])] =
          std::max(0.0, c_scaled(j) / scale(j));
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::array<double, kNoiseTerms> g = Basis(points[i].tau_s);
      double largest = -1;
      for (int t = 0; t < kNoiseTerms; ++t) {
        const double part = positive[static_cast<std::size_t>(t)] * g[static_cast<std::size_t>(t)];
        // Damped by half after the first round: a term near 0 whose sign flips would otherwise
        // take its part of the weights in and out on alternate rounds, a cycle.
        double& kept = parts[i][static_cast<std::size_t>(t)];
        kept = iteration == 1 ? part : 0.5 * (kept + part);
        if (part > largest) largest = part, out.dominant[i] = NoiseOf(t);
      }
    }
    rho = (*problem.correlation)(positive);
    out.iterations = iteration;
    // Settled: no term moved by more than 10⁻³ of its standard error (the weights' effect on the
    // estimate is of second order; the damped rounds approach it geometrically).
    bool settled = iteration > 1;
    for (Eigen::Index j = 0; j < p && settled; ++j) {
      settled = std::abs(c_scaled(j) - previous(j)) <= 1e-3 * std::sqrt(covariance_scaled(j, j));
    }
    if (settled) {
      out.converged = true;
      break;
    }
  }
  return w;
}

// Each term's interval, on its square c: c ± z σ_c, σ_c the standard error at the estimate
// (Wald), its upper end raised to the least c' with c' − c ≥ z σ_c(c'), σ_c(c') the standard
// error were the term c', the others fitted again with it held there (score). σ_c follows the
// term where the term dominates the points that determine it (a random walk at the longest τ,
// where few clusters are), and the Wald interval is then short above: the truth lay above it
// in 26 of 300 one-hour 100 Hz logs, those whose random walk came out near 0 and so weighted
// the long τ as if they were quiet (5 above the score interval). Below, the score end is no
// better: a term held at 0 leaves the others to explain the points as they can, and σ_c(0)
// follows them (the Xsens gyroscope's plain white noise, at 27 σ_c, came out within z σ_c(0)
// of 0); with no rate ramp, 11 % of ramps lay beyond 1.96 σ_c(0), none beyond 1.96 σ_c.
// Where the term does not dominate, σ_c hardly moves and the interval is c ± z σ_c.
void TermInterval(const NoiseProblem& problem, const NoiseFitOptions& options, const WeightedFit& w,
                  Eigen::Index j, double z, const std::vector<double>& limits,
                  const std::array<double, kNoiseTerms>& estimate, NoiseModelFit* fit) {
  const Eigen::VectorXd& scale = problem.scale;
  NoiseModelFit& out = *fit;
  const auto term = static_cast<std::size_t>(problem.fitted[static_cast<std::size_t>(j)]);
  NoiseTermEstimate& e = out.terms[term];
  const double c = w.c_scaled(j) / scale(j);
  const double sigma_c = std::sqrt(w.covariance_scaled(j, j)) / scale(j);
  std::array<double, kNoiseTerms> others = estimate;
  const auto z_sigma_at = [&](double c_prime) {  // z σ_c(c'), unscaled
    return z * std::sqrt(problem.ProfileVariance(j, c_prime, others, options.max_iterations)) /
           scale(j);
  };
  e.fitted = true;
  e.z = sigma_c > 0 ? c / sigma_c : 0.0;
  e.value = std::sqrt(std::max(0.0, c));
  if (c < -z * sigma_c) {
    // Below 0 beyond its interval: the Allan deviation's own bound.
    out.below_zero.push_back(static_cast<NoiseTerm>(term));
    if (options.intervals) e.high = EnvelopeBound(out, limits, term);
    return;
  }
  if (!options.intervals) {  // the estimates and their z alone
    e.resolved = c > z * sigma_c;
    e.high = std::sqrt(std::max(0.0, c + z * sigma_c));
    if (e.resolved) {
      e.low = std::sqrt(c - z * sigma_c);
      e.sigma = sigma_c / (2 * e.value);
    }
    return;
  }
  // Above (score): the least c' ≥ max(c, 0) with c' − c ≥ z σ_c(c'), bracketed by doubling up
  // to the Allan deviation's own bound, then halved to 10⁻³ of itself (40 halvings at most: a
  // root at 0 is approached by halves). None below that bound (σ_c growing as fast as c'):
  // that bound.
  const double envelope = EnvelopeBound(out, limits, term);
  const double ceiling = envelope * envelope;
  const auto holds = [&](double c_prime) { return c_prime - c >= z_sigma_at(c_prime); };
  double lo = std::max(c, 0.0), hi = lo, high = ceiling;
  if (!(lo < ceiling) || holds(lo)) {
    high = std::min(lo, ceiling);  // c < 0 and 0 within z σ_c(0) of it, or c beyond the bound
  } else {
    hi = std::min(ceiling, lo + z_sigma_at(lo));
    while (hi < ceiling && !holds(hi)) lo = hi, hi = std::min(ceiling, 2 * hi);
    if (hi < ceiling || holds(hi)) {
      for (int halving = 0; halving < 40 && hi - lo > 1e-3 * hi; ++halving) {
        const double mid = 0.5 * (lo + hi);
        (holds(mid) ? hi : lo) = mid;
      }
      high = hi;
    }
  }
  // The Wald end too. For a term not resolved, an upper bound only, not beyond the Allan
  // deviation's own bound: a ramp whose c + z σ_c would make σ(τ) 18 times what was measured
  // at the longest τ (the Xsens rest's x) bounds nothing that bound does not bound better (an
  // estimate beyond it, other terms below 0 making room, keeps its value). A resolved term's
  // Wald end is within twice its estimate, and that bound does not hold where the terms do not
  // describe the noise: the Xsens filters its output, its shortest τ fall below white noise,
  // and the white noise fitted above them lies beyond the bound the first τ set.
  e.resolved = c > z * sigma_c;
  const double wald =
      e.resolved ? c + z * sigma_c : std::min(c + z * sigma_c, std::max(ceiling, c));
  e.high = std::sqrt(std::max({0.0, high, wald}));
  if (e.resolved) {
    e.low = std::sqrt(c - z * sigma_c);
    e.sigma = sigma_c / (2 * e.value);
  }
}

NoiseModelFit FitNear1(const std::vector<AllanPoint>& points, const NoiseFitOptions& options) {
  const NoiseProblem problem(points, options);
  const std::vector<int>& fitted = problem.fitted;
  const std::size_t n = points.size();
  const auto p = static_cast<Eigen::Index>(fitted.size());
  NoiseModelFit out;
  out.points = points;
  out.edf.assign(n, 0);
  out.dominant.assign(n, PowerLawNoise::kWhite);
  const WeightedFit w = IterateWeights(problem, options, &out);
  const Eigen::VectorXd& c_scaled = w.c_scaled;
  const Eigen::VectorXd& scale = problem.scale;
  const double chi2 = w.chi2;
  out.chi2 = chi2;
  out.dof = static_cast<int>(n) - static_cast<int>(p);
  out.chi2_p = out.dof > 0 ? internal::ChiSquareSurvival(chi2, out.dof) : 1.0;
  std::array<double, kNoiseTerms> squared{};
  for (Eigen::Index j = 0; j < p; ++j) {
    squared[static_cast<std::size_t>(fitted[static_cast<std::size_t>(j)])] = c_scaled(j) / scale(j);
  }
  for (std::size_t i = 0; i < n; ++i) {
    out.model_avar.push_back(NoiseModelAvar(squared, points[i].tau_s));
    if (options.intervals) {
      out.intervals.push_back(
          AllanDeviationInterval(points[i].avar, out.edf[i], options.confidence));
    }
  }
  const double z = std::sqrt(internal::ChiSquareQuantile(1 - options.confidence, 1));
  const std::vector<double> limits =
      options.intervals ? EnvelopeLimits(out, options.confidence) : std::vector<double>{};
  std::array<double, kNoiseTerms> estimate{};
  for (Eigen::Index j = 0; j < p; ++j) {
    estimate[static_cast<std::size_t>(fitted[static_cast<std::size_t>(j)])] =
        std::max(0.0, c_scaled(j) / scale(j));
  }
  for (Eigen::Index j = 0; j < p; ++j) {
    TermInterval(problem, options, w, j, z, limits, estimate, &out);
  }
  return out;
}

}  // namespace

NoiseModelFit FitNoiseModel(const std::vector<AllanPoint>& points, const NoiseFitOptions& options) {
  // Fitted on σ² scaled by a power of 4 to near 1 and scaled back: exact in binary floating
  // point, so that the fit's weights (σ⁴) and its floors hold for readings of any magnitude in
  // which σ² itself is a number, and the result is the same as at scale 1.
  std::vector<double> positive;
  for (const AllanPoint& p : points) {
    if (p.avar > 0 && std::isfinite(p.avar)) positive.push_back(p.avar);
  }
  int k = 0;  // the scale is 4^k
  if (!positive.empty()) {
    auto middle = positive.begin() + static_cast<std::ptrdiff_t>(positive.size() / 2);
    std::nth_element(positive.begin(), middle, positive.end());
    k = static_cast<int>(std::lround(std::log2(*middle) / 2));
  }
  if (k == 0) return FitNear1(points, options);
  std::vector<AllanPoint> scaled = points;
  for (AllanPoint& p : scaled) p.avar = std::ldexp(p.avar, -2 * k);
  NoiseModelFit fit = FitNear1(scaled, options);
  fit.points = points;
  for (NoiseTermEstimate& e : fit.terms) {
    e.value = std::ldexp(e.value, k);
    e.sigma = std::ldexp(e.sigma, k);
    e.low = std::ldexp(e.low, k);
    e.high = std::ldexp(e.high, k);
  }
  for (double& v : fit.model_avar) v = std::ldexp(v, 2 * k);
  for (AllanInterval& i : fit.intervals) {
    i.low = std::ldexp(i.low, k);
    i.high = std::ldexp(i.high, k);
  }
  return fit;
}

}  // namespace accelcal
