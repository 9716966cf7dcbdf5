// The gyroscope's still run inside each still interval (gyro_still_runs.hpp).
#include "io/gyro_still_runs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/median.hpp"

namespace accelcal::internal {

namespace {

// The means of the windows [k, k + w) inside `iv`, less `centre`.
void WindowMeans(const std::vector<Vec3>& rates, const StaticInterval& iv, std::size_t w,
                 const Vec3& centre, std::vector<Vec3>* out) {
  out->clear();
  if (iv.end - iv.begin < w) return;
  Vec3 sum = Vec3::Zero();
  for (std::size_t k = iv.begin; k < iv.begin + w; ++k) sum += rates[k];
  const double inv = 1.0 / static_cast<double>(w);
  out->resize(iv.end - iv.begin - w + 1);
  Vec3* mean = out->data();
  for (std::size_t k = iv.begin;; ++k) {
    *mean++ = sum * inv - centre;
    if (k + w >= iv.end) break;
    sum += rates[k + w] - rates[k];
  }
}

}  // namespace

namespace {

// Per axis, the median of the values `use` marks (0 when none is).
Vec3 AxisMedian(const std::vector<Vec3>& values, const std::vector<char>& use) {
  Vec3 median = Vec3::Zero();
  for (int a = 0; a < 3; ++a) {
    std::vector<double> axis;
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (use[i]) axis.push_back(values[i](a));
    }
    median(a) = axis.empty() ? 0.0 : Median(std::move(axis));
  }
  return median;
}

// Each interval's median rate, per axis.
std::vector<Vec3> IntervalMedians(const std::vector<Vec3>& rates_raw,
                                  const std::vector<StaticInterval>& intervals) {
  const std::size_t m = intervals.size();
  std::vector<Vec3> centre(m);
  for (std::size_t i = 0; i < m; ++i) {
    const StaticInterval& iv = intervals[i];
    for (int a = 0; a < 3; ++a) {
      std::vector<double> axis(iv.end - iv.begin);
      for (std::size_t k = iv.begin; k < iv.end; ++k) axis[k - iv.begin] = rates_raw[k](a);
      centre[i](a) = axis.empty() ? 0.0 : Median(std::move(axis));
    }
  }
  return centre;
}

// The offset's first guess, the median of the intervals' medians; the turns' peak rate about it
// over the samples between consecutive intervals (the median over the turns: one slip of the
// hand or one slow turn does not set it).
double TurnPeak(const std::vector<Vec3>& rates_raw, const std::vector<StaticInterval>& intervals,
                const std::vector<Vec3>& centre) {
  const std::size_t m = intervals.size();
  const Vec3 offset = AxisMedian(centre, std::vector<char>(m, 1));
  std::vector<double> peaks;
  for (std::size_t i = 0; i + 1 < m; ++i) {
    double peak = 0;
    for (std::size_t k = intervals[i].end; k < intervals[i + 1].begin; ++k) {
      peak = std::max(peak, (rates_raw[k] - offset).cwiseAbs().maxCoeff());
    }
    if (intervals[i + 1].begin > intervals[i].end) peaks.push_back(peak);
  }
  return peaks.empty() ? 0.0 : Median(std::move(peaks));
}

// The longest run of an interval of `length` samples where the gyroscope is still, from its
// windows' largest deviations in σ (`sigmas`), with hysteresis: a stretch of consecutive windows
// beyond kGyroStillThreshold σ is moving when one of them is beyond kGyroMotionThreshold σ, or
// when it touches the interval's edge (a turn's end, which the accelerometer took for still: a
// slow turn's may never reach the peak inside the interval). Its length, its first sample
// (relative to the interval's) in `best_begin`; `moving` is the samples' marks, scratch space.
std::size_t LongestStillRun(const std::vector<double>& sigmas, std::size_t length, std::size_t w,
                            std::vector<char>* moving, std::size_t* best_begin) {
  moving->assign(length, 0);
  for (std::size_t j = 0; j < sigmas.size();) {
    if (!(sigmas[j] > kGyroStillThreshold)) {
      ++j;
      continue;
    }
    std::size_t end = j;
    bool motion = false;
    while (end < sigmas.size() && sigmas[end] > kGyroStillThreshold) {
      motion = motion || sigmas[end] > kGyroMotionThreshold;
      ++end;
    }
    // At the interval's edge it is a turn's end, which the accelerometer took for still
    // (a slow turn's may never reach the peak inside the interval).
    motion = motion || j == 0 || end == sigmas.size();
    if (motion) std::fill(moving->begin() + j, moving->begin() + (end - 1 + w), 1);
    j = end;
  }
  std::size_t best_length = 0;
  for (std::size_t j = 0; j < moving->size();) {
    if ((*moving)[j]) {
      ++j;
      continue;
    }
    std::size_t end = j;
    while (end < moving->size() && !(*moving)[end]) ++end;
    if (end - j > best_length) *best_begin = j, best_length = end - j;
    j = end;
  }
  return best_length;
}

// White noise's share of a window mean, from the successive differences inside the runs (a
// slow wobble hardly moves them); each run's own scatter against it.
// Which runs wobble; `means` is the window means' scratch space.
std::vector<char> Wobbles(const std::vector<Vec3>& rates_raw,
                          const std::vector<StaticInterval>& runs, std::size_t w,
                          const std::vector<Vec3>& centre, std::vector<std::vector<Vec3>>* means) {
  const std::size_t m = runs.size();
  std::vector<double> differences[3];
  std::size_t count = 0;
  for (std::size_t i = 0; i < m; ++i) {
    count += runs[i].end > runs[i].begin ? runs[i].end - runs[i].begin - 1 : 0;
  }
  for (std::vector<double>& d : differences) d.resize(count);
  std::size_t at = 0;
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t k = runs[i].begin + 1; k < runs[i].end; ++k, ++at) {
      for (int a = 0; a < 3; ++a) {
        differences[a][at] = std::abs(rates_raw[k](a) - rates_raw[k - 1](a));
      }
    }
  }
  Vec3 white = Vec3::Zero();
  for (int a = 0; a < 3; ++a) {
    if (!differences[a].empty()) {
      white(a) = Median(std::move(differences[a])) / 0.6745 / std::sqrt(2.0) /
                 std::sqrt(static_cast<double>(w));
    }
  }
  std::vector<char> wobbles(m, 0);
  for (std::size_t i = 0; i < m; ++i) {
    const StaticInterval& run = runs[i];
    if (run.end - run.begin < w + 1) continue;
    WindowMeans(rates_raw, run, w, centre[i], &(*means)[i]);
    for (int a = 0; a < 3; ++a) {
      std::vector<double> d((*means)[i].size());
      for (std::size_t j = 0; j < d.size(); ++j) d[j] = std::abs((*means)[i][j](a));
      const double own = Median(std::move(d)) / 0.6745;
      if (own > kGyroWobbleSignificance * white(a)) wobbles[i] = 1;
    }
  }
  return wobbles;
}

}  // namespace

GyroStillRuns FindGyroStillRuns(const std::vector<Vec3>& rates_raw,
                                const std::vector<StaticInterval>& intervals, double sample_step_s,
                                const Vec3& quantum_raw) {
  GyroStillRuns out;
  const std::size_t m = intervals.size();
  if (m == 0) return out;
  std::size_t shortest = std::numeric_limits<std::size_t>::max();
  for (const StaticInterval& iv : intervals) shortest = std::min(shortest, iv.end - iv.begin);
  std::size_t w = 1;
  if (sample_step_s > 0 && std::isfinite(sample_step_s)) {
    w = static_cast<std::size_t>(std::max(1.0, std::round(0.1 / sample_step_s)));
  }
  out.window = w = std::max<std::size_t>(1, std::min(w, shortest / 4));
  // First each interval's median, then its run's mean. (The mean of the interval's quietest
  // block, which would stand however much of it turns, takes a turn at a constant rate for the
  // still rate.)
  std::vector<Vec3> centre = IntervalMedians(rates_raw, intervals);
  out.turn_peak_raw = TurnPeak(rates_raw, intervals, centre);
  const double wobble_cap = kGyroWobbleFraction * out.turn_peak_raw;
  out.runs.assign(m, StaticInterval{});
  out.interval_sigma_raw.assign(m, Vec3::Zero());
  std::vector<std::vector<Vec3>> means(m);
  std::vector<double> sigmas;
  std::vector<char> moving;
  for (int pass = 0; pass < 3; ++pass) {
    // The windows' deviations: all of them at first, then those inside the runs found.
    std::vector<double> deviation[3];
    std::vector<Vec3> own(m, Vec3::Zero());
    for (std::vector<double>& d : deviation) d.reserve(rates_raw.size());
    for (std::size_t i = 0; i < m; ++i) {
      WindowMeans(rates_raw, intervals[i], w, centre[i], &means[i]);
      const StaticInterval& run = out.runs[i];
      // Written in place (sized for every window, cut to those taken): an out-of-line
      // push_back per value had cost more than the windows' sums.
      const std::size_t pooled = deviation[0].size(), windows = means[i].size();
      for (std::vector<double>& d : deviation) d.resize(pooled + windows);
      std::size_t taken = 0;
      for (std::size_t j = 0; j < windows; ++j) {
        const std::size_t k = intervals[i].begin + j;
        if (pass > 0 && !(k >= run.begin && k + w <= run.end)) continue;
        for (int a = 0; a < 3; ++a) deviation[a][pooled + taken] = std::abs(means[i][j](a));
        ++taken;
      }
      for (std::vector<double>& d : deviation) d.resize(pooled + taken);
      // The interval's own scatter, by the median of its windows' deviations (a turn's ends
      // take less than half of an interval): the values just pooled.
      for (int a = 0; a < 3; ++a) {
        const auto from = deviation[a].begin() + static_cast<std::ptrdiff_t>(pooled);
        own[i](a) =
            taken == 0 ? 0.0 : Median(std::vector<double>(from, deviation[a].end())) / 0.6745;
      }
    }
    for (int a = 0; a < 3; ++a) {
      const double floor = std::isfinite(quantum_raw(a))
                               ? quantum_raw(a) / std::sqrt(12.0 * static_cast<double>(w))
                               : 0.0;
      // First the lower quartile of |d|, 0.3186 σ for Gaussian noise: it stands while up to
      // three quarters of the windows move (a gyro leading by two thirds of each still
      // interval). Then, inside the runs, the median, 0.6745 σ: half the quartile's standard
      // error (9 % against 15 % from 150 windows).
      const double p = pass == 0 ? 0.25 : 0.5, quantile = pass == 0 ? 0.3186 : 0.6745;
      const double q = deviation[a].empty() ? 0.0 : Quantile(std::move(deviation[a]), p);
      out.window_sigma_raw(a) = std::max(q / quantile, floor);
    }
    for (std::size_t i = 0; i < m; ++i) {
      const StaticInterval& iv = intervals[i];
      // The interval's wobble, where it clearly has more than the pooled noise (an estimate
      // from a few seconds' windows is within about 30 % of it), up to the cap.
      Vec3 sigma = out.window_sigma_raw;
      for (int a = 0; a < 3; ++a) {
        if (own[i](a) > kGyroWobbleSignificance * sigma(a)) {
          sigma(a) = std::max(sigma(a), std::min(own[i](a), wobble_cap));
        }
      }
      out.interval_sigma_raw[i] = sigma;
      // Hysteresis: a stretch of consecutive windows beyond kGyroStillThreshold σ is moving
      // when one of them is beyond kGyroMotionThreshold σ.
      // Each window's largest deviation in σ.
      sigmas.resize(means[i].size());
      for (std::size_t j = 0; j < means[i].size(); ++j) {
        sigmas[j] = means[i][j].cwiseAbs().cwiseQuotient(sigma).maxCoeff();
      }
      std::size_t best_begin = 0;
      const std::size_t best_length =
          LongestStillRun(sigmas, iv.end - iv.begin, w, &moving, &best_begin);
      StaticInterval& run = out.runs[i];
      run = StaticInterval{};
      if (best_length >= 2) {
        run.begin = iv.begin + best_begin;
        run.end = run.begin + best_length;
        Vec3 mean = Vec3::Zero();
        for (std::size_t k = run.begin; k < run.end; ++k) mean += rates_raw[k];
        centre[i] = mean / static_cast<double>(best_length);
      } else {
        run.begin = run.end = iv.begin;
      }
    }
  }
  // Each run's mean against the offset, the median of the runs' means; their spread about it
  // by the median absolute deviation.
  std::vector<char> has_run(m);
  for (std::size_t i = 0; i < m; ++i) has_run[i] = out.runs[i].end > out.runs[i].begin ? 1 : 0;
  out.offset_raw = AxisMedian(centre, has_run);
  std::vector<Vec3> off(m, Vec3::Zero());
  for (std::size_t i = 0; i < m; ++i) {
    if (has_run[i]) off[i] = (centre[i] - out.offset_raw).cwiseAbs();
  }
  const Vec3 spread = AxisMedian(off, has_run) / 0.6745;
  out.wobbles = Wobbles(rates_raw, out.runs, w, centre, &means);
  out.run_offset_raw.assign(m, Vec3::Zero());
  out.run_tolerance_raw.assign(m, Vec3::Zero());
  for (std::size_t i = 0; i < m; ++i) {
    if (!has_run[i]) continue;
    const StaticInterval& run = out.runs[i];
    const double windows = static_cast<double>(run.end - run.begin) / static_cast<double>(w);
    const Vec3 own_mean = out.interval_sigma_raw[i] / std::sqrt(std::max(1.0, windows));
    const Vec3 tolerance = (kGyroOffsetSpread * spread)
                               .cwiseMax(kGyroMotionThreshold * own_mean)
                               .cwiseMax(Vec3::Constant(wobble_cap));
    out.run_offset_raw[i] = centre[i] - out.offset_raw;
    out.run_tolerance_raw[i] = tolerance;
    if (((centre[i] - out.offset_raw).cwiseAbs().array() > tolerance.array()).any()) {
      out.runs[i].end = out.runs[i].begin;
    }
  }
  return out;
}

}  // namespace accelcal::internal
