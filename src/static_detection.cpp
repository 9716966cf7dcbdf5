#include "accelcal/static_detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "accelcal/error.hpp"

namespace accelcal {

std::optional<std::string> StaticDetectionOptions::Validate() const {
  if (!(window_s > 0)) return "the detection window must be positive";
  if (!(min_duration_s >= 0)) return "the minimum static duration must be >= 0";
  if (!(threshold_factor > 0)) return "the threshold factor must be positive";
  if (!(init_rest_s >= 0)) return "the initial rest period must be >= 0";
  if (!(max_noise_ratio >= 1)) return "the maximum noise ratio must be >= 1";
  if (!(reference_quantile > 0 && reference_quantile < 1)) {
    return "the reference quantile must lie in (0, 1)";
  }
  return std::nullopt;
}

namespace {

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

// Why `interval` is clipped (RejectedInterval::Cause::kClipped), or nothing.
std::optional<std::string> Clipping(const std::vector<Vec3>& samples,
                                    const StaticInterval& interval,
                                    const std::pair<Vec3, Vec3>& extremes) {
  const std::size_t n = interval.count();
  for (int a = 0; a < 3; ++a) {
    // Another axis must vary: a noise-free (simulated) log sits still at its extremes too.
    if (!(interval.std((a + 1) % 3) > 0 || interval.std((a + 2) % 3) > 0)) continue;
    for (const bool largest : {true, false}) {
      const double limit = largest ? extremes.second(a) : extremes.first(a);
      std::size_t at_limit = 0;
      for (std::size_t i = interval.begin; i < interval.end; ++i)
        at_limit += samples[i](a) == limit;
      if (at_limit >= 3 && 100 * at_limit >= n) {
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "axis %c reads %.9g, the %s value in the log, in %.0f%% of its samples: the "
                      "sensor is saturated (clipped)",
                      "xyz"[a], limit, largest ? "largest" : "smallest",
                      100.0 * static_cast<double>(at_limit) / static_cast<double>(n));
        return std::string(buf);
      }
    }
  }
  return std::nullopt;
}
}  // namespace

StaticDetectionResult DetectStaticIntervals(const RawLog& log,
                                            const StaticDetectionOptions& options) {
  if (auto why = options.Validate()) throw DataError(*why);
  if (!log.rate_hz) {
    throw DataError("the log has no time column: give the sample rate (--rate HZ)");
  }
  StaticDetectionResult result;
  result.rate_hz = *log.rate_hz;
  const std::size_t n = log.samples.size();
  const std::size_t w = std::max<std::size_t>(
      3, static_cast<std::size_t>(std::lround(options.window_s * result.rate_hz)) | 1);
  result.window_samples = w;
  if (n < w + 1) {
    throw DataError(std::to_string(n) + " samples are fewer than one detection window (" +
                    std::to_string(w) + ")");
  }
  const std::size_t h = w / 2;

  // Sliding sums of the samples and their squares, shifted by the first sample to avoid
  // cancellation with raw counts far from zero, and of the successive differences.
  const Vec3 shift = log.samples.front();
  std::vector<double> score(n, 0.0);
  std::vector<char> white(n, 0);
  Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero(), dsum = Vec3::Zero(), dsum2 = Vec3::Zero();
  for (std::size_t i = 0; i < w; ++i) {
    const Vec3 d = log.samples[i] - shift;
    sum += d;
    sum2 += d.cwiseAbs2();
    if (i > 0) {
      const Vec3 diff = log.samples[i] - log.samples[i - 1];
      dsum += diff;
      dsum2 += diff.cwiseAbs2();
    }
  }
  const double wn = static_cast<double>(w);
  for (std::size_t c = h;; ++c) {
    const Vec3 var = (sum2 - sum.cwiseAbs2() / wn) / (wn - 1);
    const Vec3 dvar = (dsum2 - dsum.cwiseAbs2() / (wn - 1)) / (wn - 2);
    score[c] = var.cwiseMax(0.0).sum();
    white[c] = score[c] <= options.max_noise_ratio * 0.5 * dvar.cwiseMax(0.0).sum();
    if (c + h + 1 >= n) break;
    const Vec3 out = log.samples[c - h] - shift;
    const Vec3 in = log.samples[c + h + 1] - shift;
    sum += in - out;
    sum2 += in.cwiseAbs2() - out.cwiseAbs2();
    const Vec3 dout = log.samples[c - h + 1] - log.samples[c - h];
    const Vec3 din = log.samples[c + h + 1] - log.samples[c + h];
    dsum += din - dout;
    dsum2 += din.cwiseAbs2() - dout.cwiseAbs2();
  }
  const std::size_t first = h, last = n - h - 1;  // centres with a full window

  // Noise reference.
  if (options.init_rest_s > 0) {
    const std::size_t m = static_cast<std::size_t>(options.init_rest_s * result.rate_hz);
    if (m < 2 || m > n) throw DataError("the initial rest period is longer than the log");
    Vec3 mean, std;
    MeanAndStd(log.samples, 0, m, &mean, &std);
    result.noise_reference = std.cwiseAbs2().sum();
  } else {
    std::vector<double> sorted(score.begin() + static_cast<std::ptrdiff_t>(first),
                               score.begin() + static_cast<std::ptrdiff_t>(last) + 1);
    const std::size_t q = static_cast<std::size_t>(options.reference_quantile *
                                                   static_cast<double>(sorted.size() - 1));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(q), sorted.end());
    result.noise_reference = sorted[q];
  }
  // Quantised sensors can be perfectly still (zero variance): keep a floor so that the threshold
  // does not reject every window but the most perfectly silent ones.
  double floor_value = 0;
  for (int a = 0; a < 3; ++a)
    floor_value += 1.0 / 12.0 * 1e-12 * std::pow(std::abs(shift(a)) + 1.0, 2);
  result.threshold = options.threshold_factor * std::max(result.noise_reference, floor_value);

  const std::size_t min_len = std::max<std::size_t>(
      2, static_cast<std::size_t>(std::ceil(options.min_duration_s * result.rate_hz)));
  std::size_t run_start = 0;
  bool in_run = false;
  std::optional<std::pair<Vec3, Vec3>> extremes;  // of the whole log, computed when first needed
  for (std::size_t c = first; c <= last + 1; ++c) {
    const bool still = c <= last && score[c] <= result.threshold && white[c];
    if (still && !in_run) {
      run_start = c;
      in_run = true;
    } else if (!still && in_run) {
      in_run = false;
      const auto time_of = [&](std::size_t i) {
        return log.time_s.empty() ? static_cast<double>(i) / result.rate_hz : log.time_s[i];
      };
      if (c - run_start >= min_len) {
        StaticInterval interval;
        interval.begin = run_start;
        interval.end = c;
        MeanAndStd(log.samples, interval.begin, interval.end, &interval.mean, &interval.std);
        interval.t_begin_s = time_of(interval.begin);
        interval.t_end_s = time_of(interval.end - 1);
        if (!extremes) extremes = LogExtremes(log.samples);
        if (std::optional<std::string> clipped = Clipping(log.samples, interval, *extremes)) {
          result.rejected.push_back({interval.begin, interval.end, interval.t_begin_s,
                                     interval.t_end_s, RejectedInterval::Cause::kClipped,
                                     *clipped});
        } else {
          result.intervals.push_back(interval);
        }
      } else if (4 * (c - run_start) >= min_len) {
        RejectedInterval rejected;
        rejected.begin = run_start;
        rejected.end = c;
        rejected.t_begin_s = time_of(run_start);
        rejected.t_end_s = time_of(c - 1);
        char buf[120];
        std::snprintf(buf, sizeof buf, "still for %.2f s, shorter than the minimum %.2f s",
                      static_cast<double>(c - run_start) / result.rate_hz, options.min_duration_s);
        rejected.reason = buf;
        result.rejected.push_back(rejected);
      }
    }
  }
  return result;
}

}  // namespace accelcal
