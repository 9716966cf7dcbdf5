#include "accelcal/static_detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>

#include "accelcal/error.hpp"
#include "core/median.hpp"
#include "core/text_format.hpp"
#include "io/detection_kernels.hpp"

namespace accelcal {

using internal::Format;

std::optional<std::string> StaticDetectionOptions::Validate() const {
  // Finite too: an infinite window or threshold makes the whole log one still interval.
  if (!(window_s > 0) || !std::isfinite(window_s)) {
    return "the detection window must be positive and finite";
  }
  if (!(min_duration_s >= 0) || !std::isfinite(min_duration_s)) {
    return "the minimum static duration must be >= 0 and finite";
  }
  if (!(threshold_factor > 0) || !std::isfinite(threshold_factor)) {
    return "the threshold factor must be positive and finite";
  }
  if (!(init_rest_s >= 0) || !std::isfinite(init_rest_s)) {
    return "the initial rest period must be >= 0 and finite";
  }
  if (!(max_noise_ratio >= 1) || !std::isfinite(max_noise_ratio)) {
    return "the maximum noise ratio must be >= 1 and finite";
  }
  if (!(reference_quantile > 0 && reference_quantile < 1)) {
    return "the reference quantile must lie in (0, 1)";
  }
  return std::nullopt;
}

namespace {

using internal::detection::CountExtremes;
using internal::detection::ExtremeCounts;
using internal::detection::FindSmallestSteps;
using internal::detection::RunKernel;
using internal::detection::SlideWindows;
using internal::detection::SmallestSteps;
using internal::detection::WindowSums;

static_assert(sizeof(Vec3) == 3 * sizeof(double), "samples are read as x y z x y z ...");

// Per-axis mean and sample standard deviation of samples [begin, end), two-pass for accuracy.
void MeanAndStd(const std::vector<Vec3>& s, std::size_t begin, std::size_t end, Vec3* mean,
                Vec3* std) {
  Vec3 sum = Vec3::Zero();
  for (std::size_t i = begin; i < end; ++i) sum += s[i];
  const double n = static_cast<double>(end - begin);
  *mean = sum / n;
  Vec3 sq = Vec3::Zero();
  for (std::size_t i = begin; i < end; ++i) sq += (s[i] - *mean).cwiseAbs2();
  *std = n > 1 ? Vec3((sq / (n - 1)).cwiseSqrt()) : Vec3::Zero();
}

// The smallest and largest value of each axis over the whole log.
std::pair<Vec3, Vec3> LogExtremes(const std::vector<Vec3>& samples) {
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : samples) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return {lo, hi};
}

// The k-th smallest (0-based) of the non-NaN values of `v`, all >= 0, without copying them: a
// radix selection on the bit patterns, which order non-negative doubles as unsigned integers.
// Each pass counts the next 16 bits of the values that share the bits fixed so far and fixes the
// 16 bits of the bucket holding the k-th; once that bucket is small, its values are copied and
// nth_element finishes. The same value as nth_element on a copy (detection of a 1-hour log would
// otherwise hold a second copy of its scores, 29 MB); at most 65,536 values are copied at once,
// as their copy is smaller than the counts.
double KthSmallest(const std::vector<double>& v, std::size_t k) {
  const auto bits = [](double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
  };
  constexpr std::size_t kFew = std::size_t{1} << 16;
  // nth_element on a copy of the `total` values that `matches`.
  const auto select = [&](std::size_t total, const auto& matches) {
    std::vector<double> kept;
    kept.reserve(total);
    for (double x : v) {
      if (matches(x)) kept.push_back(x);
    }
    std::nth_element(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(k), kept.end());
    return kept[k];
  };
  if (v.size() <= kFew) return select(v.size(), [](double x) { return !std::isnan(x); });
  std::uint64_t prefix = 0;
  std::vector<std::size_t> count(1 << 16);
  for (int shift = 48;; shift -= 16) {
    // Values whose bits above shift + 16 equal the prefix's.
    const auto matches = [&](double x) {
      return !std::isnan(x) &&
             (shift == 48 || (bits(x) >> (shift + 16)) == (prefix >> (shift + 16)));
    };
    std::fill(count.begin(), count.end(), 0);
    std::size_t total = 0;
    for (double x : v) {
      if (!matches(x)) continue;
      ++count[(bits(x) >> shift) & 0xFFFF];
      ++total;
    }
    if (total <= kFew || shift == 0) return select(total, matches);
    std::size_t bucket = 0;
    while (k >= count[bucket]) k -= count[bucket++];
    prefix |= static_cast<std::uint64_t>(bucket) << shift;
  }
}

// The reading of 1 g, roughly, for judging motion: a calibration log turns every axis through
// about ±1 g, so half the 2nd-98th percentile range of each axis, the median over the axes
// (exact for the positions alone; motion widens the range a little).
// Every k-th sample is enough for these percentiles (at most 8192 of them: a rough scale, cheap
// for any log).
double GravityReading(const std::vector<Vec3>& samples) {
  const std::size_t stride = samples.size() / 8192 + 1;
  std::vector<double> column((samples.size() + stride - 1) / stride);
  double half_range[3];
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < column.size(); ++i) column[i] = samples[i * stride](a);
    const auto at = [&](double q) {
      const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(column.size() - 1));
      std::nth_element(column.begin(), column.begin() + k, column.end());
      return column[static_cast<std::size_t>(k)];
    };
    const double lo = at(0.02), hi = at(0.98);
    half_range[a] = 0.5 * (hi - lo);
  }
  std::sort(half_range, half_range + 3);
  return half_range[1];
}

// Why `interval` is clipped (RejectedInterval::Cause::kClipped), or nothing.
std::optional<std::string> Clipping(const std::vector<Vec3>& samples,
                                    const StaticInterval& interval,
                                    const std::pair<Vec3, Vec3>& extremes,
                                    const Vec3& quantisation_step) {
  const std::size_t n = interval.count();
  // Another axis must vary by more than its quantisation step: a noise-free (simulated) log
  // sits still at its extremes too, and so does the +1 g reading of a quantised sensor whose
  // noise is below its step (it is the log's largest value when no motion exceeds 1 g).
  // (A constant axis's standard deviation is round-off, not variation.)
  bool varies[3], tested[3];
  for (int i = 0; i < 3; ++i) {
    varies[i] = interval.std(i) > std::max(quantisation_step(i), 1e-9 * std::abs(interval.mean(i)));
  }
  for (int a = 0; a < 3; ++a) tested[a] = varies[(a + 1) % 3] || varies[(a + 2) % 3];
  if (!tested[0] && !tested[1] && !tested[2]) return std::nullopt;
  // The samples at each axis's largest and smallest value, in one pass.
  ExtremeCounts counts{samples.data(),  interval.begin, interval.end,
                       extremes.second, extremes.first, {}};
  RunKernel<CountExtremes>(counts);
  const auto& at = counts.at;
  for (int a = 0; a < 3; ++a) {
    if (!tested[a]) continue;
    for (const bool largest : {true, false}) {
      const double limit = largest ? extremes.second(a) : extremes.first(a);
      const std::size_t at_limit = at[a][largest ? 0 : 1];
      if (at_limit >= 3 && 100 * at_limit >= n) {
        return Format(
            "axis %c reads %.9g, the %s value in the log, in %.0f%% of its samples: the sensor "
            "is saturated (clipped)",
            "xyz"[a], limit, largest ? "largest" : "smallest",
            100.0 * static_cast<double>(at_limit) / static_cast<double>(n));
      }
    }
  }
  return std::nullopt;
}

// Why `interval` is not still although every window in it is quiet (RejectedInterval::Cause::
// kMoving), or nothing. A slow turn adds little variance to a short window but moves the mean
// steadily: the interval is cut into kBatches batches, and on every axis the least-squares slope
// of the batch means against their index is tested against the scatter of the batch means about
// that line (t with kBatches − 2 degrees of freedom; batch means absorb the correlation of
// successive samples). The scatter is floored by the quantisation noise q²/12 of one sample.
// A significant slope is motion only when the mean turns faster than kMaxTurnRate_rad_s (the
// change of the mean relative to `gravity_raw`, the reading of 1 g, over the period's duration):
// still periods drift too, but slowly (a bias settling by 1 mg over the T265's 50-s rest:
// 0.001 deg/s; 1.2 counts over 11 s of the Xsens: 0.002 deg/s), while a sensor turned by hand
// moves at degrees per second (a phone settling through 2.1 deg in 1.4 s, 1.6 deg/s; a slow
// continuous rotation, 1-8 deg/s, whose windows each look still).
std::optional<std::string> Moving(const std::vector<Vec3>& samples, const StaticInterval& interval,
                                  const Vec3& quantisation_step, double gravity_raw,
                                  double rate_hz) {
  constexpr double kDegPerRad = 180 / 3.14159265358979323846;
  constexpr double kMaxTurnRate_rad_s = 0.5 / kDegPerRad;
  constexpr int kBatches = 8;
  // |t| beyond which the mean moves: t with 6 degrees of freedom exceeds 12 with probability
  // 2e-5 (two-sided), 6e-5 over the three axes.
  constexpr double kMaxT = 12.0;
  const std::size_t n = interval.count();
  if (n < 4 * kBatches) return std::nullopt;
  double y[3][kBatches];
  for (int j = 0; j < kBatches; ++j) {
    const std::size_t b = interval.begin + n * static_cast<std::size_t>(j) / kBatches;
    const std::size_t e = interval.begin + n * static_cast<std::size_t>(j + 1) / kBatches;
    Vec3 sum = Vec3::Zero();
    for (std::size_t i = b; i < e; ++i) sum += samples[i] - interval.mean;
    for (int a = 0; a < 3; ++a) y[a][j] = sum(a) / static_cast<double>(e - b);
  }
  const double xm = 0.5 * (kBatches - 1);
  double sxx = 0;
  for (int j = 0; j < kBatches; ++j) sxx += (j - xm) * (j - xm);
  const double per_batch = static_cast<double>(n) / kBatches;
  for (int a = 0; a < 3; ++a) {
    double ym = 0, sxy = 0;
    for (int j = 0; j < kBatches; ++j) ym += y[a][j] / kBatches;
    for (int j = 0; j < kBatches; ++j) sxy += (j - xm) * (y[a][j] - ym);
    const double slope = sxy / sxx;
    double rss = 0;
    for (int j = 0; j < kBatches; ++j) {
      const double r = y[a][j] - ym - slope * (j - xm);
      rss += r * r;
    }
    const double var = std::max(rss / (kBatches - 2),
                                quantisation_step(a) * quantisation_step(a) / 12.0 / per_batch);
    const double t = var > 0 ? slope / std::sqrt(var / sxx) : (slope != 0 ? INFINITY : 0.0);
    // From the first batch's centre to the last's: 7/8 of the period.
    const double moved = slope * (kBatches - 1);
    const double seconds = static_cast<double>(n) / rate_hz * (kBatches - 1) / kBatches;
    const double turn_rate = std::abs(moved) / gravity_raw / seconds;
    if (std::abs(t) > kMaxT && turn_rate > kMaxTurnRate_rad_s) {
      return Format(
          "axis %c moves by %.4g in %.3g s (%.2g deg/s of a %.4g reading of 1 g; t = %.3g): the "
          "sensor was turning, not still",
          "xyz"[a], moved, seconds, turn_rate * kDegPerRad, gravity_raw, t);
    }
  }
  return std::nullopt;
}

}  // namespace

std::string NoStaticIntervalReason(const StaticDetectionResult& d) {
  std::size_t moving = 0;
  for (const RejectedInterval& r : d.rejected) {
    moving += r.cause == RejectedInterval::Cause::kMoving;
  }
  if (moving > 0) {
    return Format(
        "no static interval found: %zu quiet period%s rejected because the sensor was "
        "turning through it (a log in continuous motion has no static positions)",
        moving, moving == 1 ? " was" : "s were");
  }
  return Format("no static interval found (threshold %.3g raw^2)", d.threshold);
}

std::vector<std::size_t> CorruptedReadings(const std::vector<Vec3>& samples, const Vec3& step) {
  const std::size_t n = samples.size();
  // The median and spread from 2048 to 4095 readings spread over the log (all of a shorter one): a
  // spread to a factor of a million needs no more, and below 4096 Median partially sorts them
  // without its counting pass over 65,536 buckets, which pays only on longer samples (that pass
  // had cost 3.9 M instructions on the Xsens recording).
  const std::size_t stride = std::max<std::size_t>(1, n / 2048);
  std::vector<double> values;
  Vec3 center = Vec3::Zero(), bound = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (int a = 0; a < 3; ++a) {
    values.clear();
    for (std::size_t i = 0; i < n; i += stride) {
      if (std::isfinite(samples[i](a))) values.push_back(samples[i](a));
    }
    if (values.empty()) continue;
    const double median = internal::Median(values);
    for (double& v : values) v = std::abs(v - median);
    const double spread =
        std::max({internal::Median(std::move(values)), step(a), 1e-12 * (std::abs(median) + 1)});
    center(a) = median;
    bound(a) = kCorruptedReadingFactor * spread;
  }
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = (samples[i] - center).cwiseAbs();
    if (!(d(0) <= bound(0) && d(1) <= bound(1) && d(2) <= bound(2))) out.push_back(i);
  }
  return out;
}

namespace {

// The detection window in samples (odd), and the shortest interval's (`min_samples`): a window
// or a minimum duration the rate cannot honour is an error, never a clamp.
std::size_t WindowSamples(const StaticDetectionOptions& options, double rate_hz, std::size_t n,
                          double* min_samples) {
  const double window_samples = options.window_s * rate_hz;
  if (!(window_samples >= 3)) {
    throw DataError(
        Format("a detection window of %.6g s holds %.3g samples at %.6g Hz; it needs "
               "at least 3",
               options.window_s, window_samples, rate_hz));
  }
  if (!(window_samples <= static_cast<double>(n))) {
    throw DataError(
        Format("%zu samples are fewer than one detection window (%.6g s = %.6g samples)", n,
               options.window_s, window_samples));
  }
  *min_samples = options.min_duration_s * rate_hz;
  if (options.min_duration_s > 0 && *min_samples < 2) {
    throw DataError(
        Format("a minimum static duration of %.6g s is %.3g samples at %.6g Hz; an "
               "interval needs at least 2",
               options.min_duration_s, *min_samples, rate_hz));
  }
  if (!(*min_samples <= static_cast<double>(n))) {  // also keeps the casts below defined
    throw DataError(
        Format("a minimum static duration of %.6g s is longer than the log (%zu "
               "samples at %.6g Hz)",
               options.min_duration_s, n, rate_hz));
  }
  return static_cast<std::size_t>(std::lround(window_samples)) | 1;
}

// Sliding sums of the samples and their squares, shifted by the first sample of the segment to
// avoid cancellation with raw counts far from zero, and of the successive differences. Centres
// without a full window inside their segment keep score NaN: no window crosses a gap. Returns
// how many centres were scored.
std::size_t ScoreWindows(const RawLog& log, const std::vector<std::size_t>& segments, std::size_t w,
                         double max_noise_ratio, double quantisation_variance,
                         std::vector<double>* score, std::vector<char>* white) {
  const std::size_t n = log.samples.size();
  const std::size_t h = w / 2;
  const double wn = static_cast<double>(w);
  std::size_t valid = 0;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const std::size_t begin = segments[s];
    const std::size_t end = s + 1 < segments.size() ? segments[s + 1] : n;
    if (end - begin < w + 1) continue;
    const Vec3 shift = log.samples[begin];
    Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero(), dsum = Vec3::Zero(), dsum2 = Vec3::Zero();
    for (std::size_t i = begin; i < begin + w; ++i) {
      const Vec3 d = log.samples[i] - shift;
      sum += d;
      sum2 += d.cwiseAbs2();
      if (i > begin) {
        const Vec3 diff = log.samples[i] - log.samples[i - 1];
        dsum += diff;
        dsum2 += diff.cwiseAbs2();
      }
    }
    WindowSums sums{log.samples.data(),
                    begin,
                    end,
                    h,
                    shift,
                    sum,
                    sum2,
                    dsum,
                    dsum2,
                    wn,
                    max_noise_ratio,
                    quantisation_variance,
                    score->data(),
                    white->data(),
                    0};
    RunKernel<SlideWindows>(sums);
    valid += sums.valid;
  }
  return valid;
}

// A still period split by a short disturbance (a glitch, a bump that did not move the sensor)
// is one orientation: two intervals at most a window apart whose means agree within 5 standard
// errors on every axis (plus one quantisation step) are joined. The joined interval spans both
// and the disturbance; its mean and standard deviation are those of the two parts' samples.
std::vector<StaticInterval> JoinSplitIntervals(const std::vector<StaticInterval>& intervals,
                                               const std::vector<std::size_t>& segments,
                                               std::size_t w, const Vec3& step,
                                               std::size_t* count) {
  std::vector<StaticInterval> joined;
  for (const StaticInterval& cur : intervals) {
    if (!joined.empty()) {
      StaticInterval& prev = joined.back();
      const double n1 = static_cast<double>(prev.count()), n2 = static_cast<double>(cur.count());
      // Never across a time gap: the first sample after a gap starts a segment.
      const bool gap_between =
          std::any_of(segments.begin(), segments.end(),
                      [&](std::size_t start) { return start >= prev.end && start <= cur.begin; });
      bool same = cur.begin - prev.end <= w && !gap_between;
      for (int a = 0; a < 3 && same; ++a) {
        const double se = std::sqrt(prev.std(a) * prev.std(a) / n1 + cur.std(a) * cur.std(a) / n2);
        same = std::abs(prev.mean(a) - cur.mean(a)) <= 5 * se + step(a);
      }
      if (same) {
        const double total = n1 + n2;
        const Vec3 mean = (n1 * prev.mean + n2 * cur.mean) / total;
        const Vec3 ss = (n1 - 1) * prev.std.cwiseAbs2() + (n2 - 1) * cur.std.cwiseAbs2() +
                        (n1 * n2 / total) * (prev.mean - cur.mean).cwiseAbs2();
        const std::size_t parts = prev.count() + cur.count();
        prev.end = cur.end;
        prev.t_end_s = cur.t_end_s;
        prev.mean = mean;
        prev.std = (ss / (total - 1)).cwiseSqrt();
        prev.averaged = parts;
        ++*count;
        continue;
      }
    }
    joined.push_back(cur);
  }
  return joined;
}

// Each interval's temperature: the mean of its samples' that have one.
void IntervalTemperatures(const RawLog& log, std::vector<StaticInterval>* intervals) {
  if (log.temperature_c.size() == log.samples.size()) {
    for (StaticInterval& interval : *intervals) {
      double sum = 0;
      std::size_t known = 0;
      for (std::size_t i = interval.begin; i < interval.end; ++i) {
        if (!std::isnan(log.temperature_c[i])) sum += log.temperature_c[i], ++known;
      }
      if (known > 0) interval.temperature_c = sum / static_cast<double>(known);
    }
  }
}

}  // namespace

StaticDetectionResult DetectStaticIntervals(const RawLog& log,
                                            const StaticDetectionOptions& options) {
  if (auto why = options.Validate()) throw DataError(*why);
  if (!log.rate_hz) throw DataError("the log has no time column and no sample rate was given");
  StaticDetectionResult result;
  result.rate_hz = *log.rate_hz;
  const std::size_t n = log.samples.size();
  double min_samples = 0;
  const std::size_t w = WindowSamples(options, result.rate_hz, n, &min_samples);
  result.window_samples = w;
  std::vector<std::size_t> segments =
      log.time ? SegmentStarts(log.time->gaps) : std::vector<std::size_t>{0};
  result.segments = segments.size();

  // Quantisation: a sensor (or a log written with few decimals) whose noise is below its step
  // reads the same value for many samples; its window variances are 0 or a few steps². The
  // floor of every noise level is the quantisation noise q²/12 of each axis, with q the smallest
  // nonzero change between successive samples.
  SmallestSteps steps{&log.samples, Vec3::Zero()};
  RunKernel<FindSmallestSteps>(steps);
  Vec3 step = steps.step;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(step(a))) step(a) = 0;
  }
  result.quantisation_step = step;
  const double quantisation_variance = step.cwiseAbs2().sum() / 12.0;

  // A corrupted reading is cut out as a gap is: a segment of its own, too short for a window.
  result.corrupted = CorruptedReadings(log.samples, step);
  if (!result.corrupted.empty()) {
    for (std::size_t i : result.corrupted) {
      segments.push_back(i);
      if (i + 1 < n) segments.push_back(i + 1);
    }
    std::sort(segments.begin(), segments.end());
    segments.erase(std::unique(segments.begin(), segments.end()), segments.end());
  }

  std::vector<double> score(n, std::nan(""));
  std::vector<char> white(n, 0);
  const std::size_t valid = ScoreWindows(log, segments, w, options.max_noise_ratio,
                                         quantisation_variance, &score, &white);
  if (valid == 0) {
    throw DataError(Format(
        "no segment of the log is longer than one detection window (%zu "
        "samples): the gaps%s cut it into %zu pieces",
        w,
        result.corrupted.empty() ? ""
                                 : Format(" and %zu corrupted readings (sample %zu the first)",
                                          result.corrupted.size(), result.corrupted.front() + 1)
                                       .c_str(),
        segments.size()));
  }

  // Noise reference.
  if (options.init_rest_s > 0) {
    const double rest_samples = options.init_rest_s * result.rate_hz;
    const std::size_t first_end = segments.size() > 1 ? segments[1] : n;
    if (!(rest_samples <= static_cast<double>(first_end)) || rest_samples < 2) {
      throw DataError(
          rest_samples > static_cast<double>(n) ? "the initial rest period is longer than the log"
          : rest_samples < 2 ? "the initial rest period holds fewer than 2 samples"
                             : "the initial rest period is longer than the log's first segment");
    }
    const auto m = static_cast<std::size_t>(rest_samples);
    Vec3 mean, std;
    MeanAndStd(log.samples, 0, m, &mean, &std);
    result.noise_reference = std.cwiseAbs2().sum();
  } else {
    const std::size_t q =
        static_cast<std::size_t>(options.reference_quantile * static_cast<double>(valid - 1));
    result.noise_reference = KthSmallest(score, q);
  }
  // Quantised sensors can be perfectly still (zero variance): the floor is their quantisation
  // noise, and a round-off floor for noise-free (simulated) data.
  // The first reading that is not corrupted (a corrupted one would make the floor absurd).
  std::size_t first = 0;
  for (std::size_t i : result.corrupted) first += i == first;
  const Vec3 shift = log.samples[std::min(first, n - 1)];
  double floor_value = quantisation_variance;
  for (int a = 0; a < 3; ++a)
    floor_value += 1.0 / 12.0 * 1e-12 * std::pow(std::abs(shift(a)) + 1.0, 2);
  result.threshold = options.threshold_factor * std::max(result.noise_reference, floor_value);

  const std::size_t min_len =
      std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(min_samples)));
  const auto time_of = [&](std::size_t i) {
    return log.time_s.empty() ? static_cast<double>(i) / result.rate_hz : log.time_s[i];
  };
  std::size_t run_start = 0;
  bool in_run = false;
  std::optional<std::pair<Vec3, Vec3>> extremes;  // of the whole log, computed when first needed
  std::optional<double> gravity_raw;              // likewise
  for (std::size_t c = 0; c <= n; ++c) {
    const bool still = c < n && !std::isnan(score[c]) && score[c] <= result.threshold && white[c];
    if (still && !in_run) {
      run_start = c;
      in_run = true;
    } else if (!still && in_run) {
      in_run = false;
      if (c - run_start >= min_len) {
        StaticInterval interval;
        interval.begin = run_start;
        interval.end = c;
        MeanAndStd(log.samples, interval.begin, interval.end, &interval.mean, &interval.std);
        interval.t_begin_s = time_of(interval.begin);
        interval.t_end_s = time_of(interval.end - 1);
        if (!extremes) extremes = LogExtremes(log.samples);
        if (!gravity_raw) gravity_raw = GravityReading(log.samples);
        std::optional<std::string> clipped = Clipping(log.samples, interval, *extremes, step);
        std::optional<std::string> moving =
            clipped ? std::nullopt
                    : Moving(log.samples, interval, step, *gravity_raw, result.rate_hz);
        if (clipped || moving) {
          result.rejected.push_back(
              {interval.begin, interval.end, interval.t_begin_s, interval.t_end_s,
               clipped ? RejectedInterval::Cause::kClipped : RejectedInterval::Cause::kMoving,
               clipped ? *clipped : *moving});
        } else {
          result.intervals.push_back(interval);
        }
      } else if (4 * (c - run_start) >= min_len) {
        RejectedInterval rejected;
        rejected.begin = run_start;
        rejected.end = c;
        rejected.t_begin_s = time_of(run_start);
        rejected.t_end_s = time_of(c - 1);
        rejected.reason =
            Format("still for %.2f s, shorter than the minimum %.2f s",
                   static_cast<double>(c - run_start) / result.rate_hz, options.min_duration_s);
        result.rejected.push_back(rejected);
      }
    }
  }
  result.intervals = JoinSplitIntervals(result.intervals, segments, w, step, &result.joined);
  IntervalTemperatures(log, &result.intervals);
  return result;
}

}  // namespace accelcal
