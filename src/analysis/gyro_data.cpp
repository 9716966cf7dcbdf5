// The gyroscope's data from a recording (gyro_data.hpp): the still rates, the turns between
// positions and where the gyro is still, checked for gaps and saturation, and the check that the
// gyroscope's log and the accelerometer's are on one clock (CheckGyroClock).
#include "analysis/gyro_data.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <Eigen/Geometry>

#include "accelcal/error.hpp"
#include "accelcal/model.hpp"
#include "core/text_format.hpp"
#include "io/gyro_still_runs.hpp"
#include "statistics/rounding.hpp"

namespace accelcal {

namespace {

using internal::AxisName;
using internal::GyroFitData;
using internal::GyroMotion;
using internal::GyroStill;
using internal::Num;

constexpr double kPi = 3.14159265358979323846;

/// A turn is integrated from the mean orientation over this much of the still span before it to
/// that over as much of the one after it [s]: a unit's wobble as it stands (0.3-1 Hz by hand)
/// averages over it, and the Earth's horizontal rate (15 °/h, not modelled) adds 0.004° at most.
constexpr double kMeanOrientationSpan_s = 2.0;

// The times the rates are integrated at: the gyro's timestamps when every step is positive, else
// (timestamps coarser than the samples, repeated) the sample index at the log's rate; the
// accelerometer's (the same clock) when the gyro's log has no time column.
std::vector<double> IntegrationTimes(const RawLog& gyro, const RawLog& accel) {
  const RawLog& log = gyro.time_s.empty() && !gyro.rate_hz ? accel : gyro;
  bool increasing = !log.time_s.empty();
  for (std::size_t k = 1; increasing && k < log.time_s.size(); ++k) {
    increasing = log.time_s[k] > log.time_s[k - 1];
  }
  if (increasing) return log.time_s;
  if (!log.rate_hz || !(*log.rate_hz > 0)) {
    throw DataError("the log " + log.source +
                    " has no time column and no sample rate: the rates cannot be integrated");
  }
  std::vector<double> t(log.samples.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) / *log.rate_hz;
  return t;
}

// A run of samples at an axis' extreme. On an axis noisier than its resolution q (σ√2 ≥ q, q its
// smallest step anywhere), consecutive readings of a flat signal repeat a value with probability
// about p = q/(2√π σ); a saturated axis repeats its rail exactly. So the run is saturation when
// p^(L−1) ≤ kSaturationFalseAlarm for its length L (three at least): at σ = 2 q, p = 0.14 and L
// ≥ 9 (seven in a row were seen at the calm peak of a simulated MPU-6050 turn); at the Xsens's
// σ = 27 counts, L ≥ 4. On a coarser axis, whose smooth peak may hold a value for a while, a run
// of at least three is saturation when one of the two steps into it or out of it is beyond
// kSaturationSteepness resolution steps (a smooth peak is approached by steps of about one).
constexpr double kSaturationFalseAlarm = 1e-6;
constexpr std::size_t kSaturatedRun = 3;
constexpr double kSaturationSteepness = 3.0;
// An analogue rail is not one value: the readings on it keep a little noise of their own (a few
// counts where the sensor's is tens), so a rail is also a plateau: readings within
// kRailBand σ of the axis' extreme, where noise puts a reading with probability at most
// p = kRailBand/√(2π) (0.1: L ≥ 7 by the rule above). A smooth peak stays near its top too, for
// longer the finer the sampling, but it is round: the run within the band is then at most
// 1/√kRailFlatness of the run within kRailFlatness times the band (a parabola's), where a rail,
// entered and left at the turn's rate, keeps nearly all of it. A plateau is saturation when its
// run is at least kRailKept of the wider one.
constexpr double kRailBand = 0.25;
constexpr double kRailFlatness = 8.0;
constexpr double kRailKept = 0.6;

struct ClippedRun {
  std::size_t begin = 0, end = 0;  // samples [begin, end)
};

// A run of at least `min_run` at the extreme: with `band` 0, of one value, entered or left by a
// step beyond `steep` (< 0: any) in its two steps before or after; with `band` > 0, of readings
// within `band` of the extreme, at least kRailKept of the run within kRailFlatness times it.
std::optional<ClippedRun> FindClippedRun(const std::vector<Vec3>& samples, std::size_t first,
                                         std::size_t last, int axis, double lo, double hi,
                                         std::size_t min_run, double steep, double band = 0) {
  if (!(hi > lo)) return std::nullopt;
  // Within `width` of the extreme the reading at k is at (+1 the top, -1 the bottom, 0 neither).
  const auto side = [&](std::size_t k, double width) {
    const double v = samples[k](axis);
    return v >= hi - width ? 1 : v <= lo + width ? -1 : 0;
  };
  for (std::size_t k = first; k <= last;) {
    const int at = side(k, band);
    if (at == 0) {
      ++k;
      continue;
    }
    std::size_t end = k;
    if (band > 0) {
      while (end <= last && side(end, band) == at) ++end;
    } else {
      while (end <= last && samples[end](axis) == samples[k](axis)) ++end;
    }
    if (end - k >= min_run) {
      if (band > 0) {
        std::size_t wide_begin = k, wide_end = end;
        while (wide_begin > first && side(wide_begin - 1, kRailFlatness * band) == at) --wide_begin;
        while (wide_end <= last && side(wide_end, kRailFlatness * band) == at) ++wide_end;
        if (static_cast<double>(end - k) >=
            kRailKept * static_cast<double>(wide_end - wide_begin)) {
          return ClippedRun{k, end};
        }
        k = end;
        continue;
      }
      // The two steps into the run and the two out of it: the step onto the rail itself is cut
      // short by it (a count, when the reading before fell just below it).
      const auto jump = [&](std::size_t a) {  // from sample a to a + 1
        return std::abs(samples[a + 1](axis) - samples[a](axis));
      };
      double step = 0;
      if (k >= 1) step = std::max(step, jump(k - 1));
      if (k >= 2) step = std::max(step, jump(k - 2));
      if (end < samples.size()) step = std::max(step, jump(end - 1));
      if (end + 1 < samples.size()) step = std::max(step, jump(end));
      if (step > steep) return ClippedRun{k, end};
    }
    k = end;
  }
  return std::nullopt;
}

std::string LineOf(const RawLog& log, std::size_t k) {
  return std::to_string(log.line.empty() ? k + 1 : log.line[k]);
}

// Every position has an interval of the log, within the gyroscope's, in time order.
void CheckPositions(const std::vector<Position>& positions, const RawLog& gyro) {
  const std::size_t m = positions.size();
  for (std::size_t i = 0; i < m; ++i) {
    if (!positions[i].interval) {
      throw DataError("position " + std::to_string(i + 1) +
                      " has no interval of the log: the gyroscope is calibrated from a raw log "
                      "only");
    }
    if (i > 0 && positions[i].interval->begin < positions[i - 1].interval->end) {
      throw DataError(
          "the positions are not in time order: the gyroscope is calibrated from "
          "one raw log");
    }
    if (positions[i].interval->end > gyro.samples.size()) {
      throw DataError("position " + std::to_string(i + 1) + " ends beyond the gyroscope's log");
    }
  }
}

// The smallest step each axis makes anywhere (its resolution, when quantised).
Vec3 Quantum(const std::vector<Vec3>& samples) {
  Vec3 quantum = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (std::size_t k = 1; k < samples.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      const double d = std::abs(samples[k](a) - samples[k - 1](a));
      if (d > 0 && d < quantum(a)) quantum(a) = d;
    }
  }
  return quantum;
}

// A saturated axis holds its extreme for several samples, entered or left steeply; the peak of
// a smooth turn on a quantised axis may repeat its extreme too, but the steps around it are of
// the noise's and the resolution's size.
// Per axis, the run at the extreme and the step into or out of it that mark saturation.
// And on an axis whose noise is four resolution steps or more, a plateau (a rail with noise
// of its own): `band` its width, `plateau_run` its length.
struct Saturation {
  Saturation(const std::vector<Vec3>& samples, const Vec3& quantum, const Vec3& noise_sigma_raw)
      : lo(samples.front()), hi(samples.front()) {
    for (const Vec3& s : samples) {
      lo = lo.cwiseMin(s);
      hi = hi.cwiseMax(s);
    }
    const auto run_for = [](double p) {
      const double length = 1 + std::log(kSaturationFalseAlarm) / std::log(p);
      return std::max(kSaturatedRun, static_cast<std::size_t>(std::ceil(length)));
    };
    for (int a = 0; a < 3; ++a) {
      const double sigma = noise_sigma_raw(a);
      plateau_run[a] = run_for(kRailBand / std::sqrt(2 * kPi));
      if (!std::isfinite(quantum(a)) || std::sqrt(2.0) * sigma >= quantum(a)) {
        min_run[a] = run_for(std::min(0.5, quantum(a) / (2 * std::sqrt(kPi) * sigma)));
        steep(a) = -1.0;
        if (!(kRailBand * sigma <= quantum(a))) band(a) = kRailBand * sigma;
      } else {
        min_run[a] = kSaturatedRun;
        steep(a) = kSaturationSteepness * quantum(a);
      }
    }
  }

  // Refuses a turn (samples first..last, from position i to next) on an axis that saturated.
  void Refuse(const RawLog& gyro, std::size_t first, std::size_t last, std::size_t i,
              std::size_t next) const;

  Vec3 lo, hi;  // the log's extremes
  std::size_t min_run[3], plateau_run[3];
  Vec3 steep, band = Vec3::Zero();
};

void Saturation::Refuse(const RawLog& gyro, std::size_t first, std::size_t last, std::size_t i,
                        std::size_t next) const {
  for (int a = 0; a < 3; ++a) {
    if (const std::optional<ClippedRun> run =
            FindClippedRun(gyro.samples, first, last, a, lo(a), hi(a), min_run[a], steep(a))) {
      throw DataError("the gyroscope's " + AxisName(a) + " axis holds the log's extreme (" +
                      Num(gyro.samples[run->begin](a), 6) + ") for " +
                      std::to_string(run->end - run->begin) +
                      " samples in a row during the turn from position " + std::to_string(i + 1) +
                      " to " + std::to_string(next + 1) + " (lines " + LineOf(gyro, run->begin) +
                      "-" + LineOf(gyro, run->end - 1) + " of " + gyro.source +
                      "): it saturated, so the turn's angle is wrong");
    }
    if (band(a) > 0) {
      if (const std::optional<ClippedRun> run = FindClippedRun(
              gyro.samples, first, last, a, lo(a), hi(a), plateau_run[a], -1.0, band(a))) {
        const bool top = gyro.samples[run->begin](a) >= hi(a) - band(a);
        throw DataError(
            "the gyroscope's " + AxisName(a) + " axis stays within " + Num(band(a), 3) +
            " (a quarter of its noise) of the log's extreme (" + Num(top ? hi(a) : lo(a), 6) +
            ") for " + std::to_string(run->end - run->begin) +
            " samples in a row during the turn from position " + std::to_string(i + 1) + " to " +
            std::to_string(next + 1) + " (lines " + LineOf(gyro, run->begin) + "-" +
            LineOf(gyro, run->end - 1) + " of " + gyro.source +
            "), a flat plateau where a turn's peak is round: it saturated, so the turn's angle "
            "is wrong");
      }
    }
  }
}

// Each still position's mean rate and the pooled sample noise, and each still mean's σ.
void StillRates(const RawLog& gyro, const internal::GyroStillRuns& still,
                const std::vector<std::size_t>& standing, const CalibrationResult& accel_cal,
                const Vec3& quantum, GyroFitData* data) {
  const std::size_t m = accel_cal.directions.size();  // the positions' count (BuildData checks)
  Vec3 sum_sq = Vec3::Zero();
  double dof = 0;
  for (const std::size_t i : standing) {
    const StaticInterval& iv = still.runs[i];
    Vec3 mean = Vec3::Zero();
    for (std::size_t k = iv.begin; k < iv.end; ++k) mean += gyro.samples[k];
    const auto n = static_cast<double>(iv.end - iv.begin);
    mean /= n;
    for (std::size_t k = iv.begin; k < iv.end; ++k) {
      sum_sq += (gyro.samples[k] - mean).cwiseAbs2();
    }
    dof += n - 1;
    data->stills.push_back({mean, Vec3::Zero(), accel_cal.gravity * accel_cal.directions[i], i});
  }
  for (std::size_t i = 0; i < m; ++i) data->directions.push_back(accel_cal.directions[i]);
  if (!(dof > 0)) throw DataError("the still positions are too short to measure the rate noise");
  data->noise_sigma_raw = (sum_sq / dof).cwiseSqrt();
  for (int a = 0; a < 3; ++a) {
    if (!(data->noise_sigma_raw(a) > 0)) {
      throw DataError("the gyroscope's " + AxisName(a) +
                      " axis reads the same value throughout every still position: its noise, "
                      "and so the weight of its readings, is unknown (a constant or missing "
                      "column?)");
    }
  }
  // Each still mean's σ: the noise over its samples, and at least what rounding to the axis'
  // step leaves when the rates do not dither (statistics/rounding.hpp).
  Vec3 rounding = Vec3::Zero();
  for (int a = 0; a < 3; ++a) {
    rounding(a) = internal::RoundingFloorVariance(
        quantum(a), data->noise_sigma_raw(a) * data->noise_sigma_raw(a));
  }
  for (GyroStill& s : data->stills) {
    const StaticInterval& iv = still.runs[s.position];
    s.sigma_mean_raw =
        (data->noise_sigma_raw.cwiseAbs2() / static_cast<double>(iv.end - iv.begin) + rounding)
            .cwiseSqrt();
  }
}

}  // namespace

namespace internal {

std::string Num(double x, int digits) { return internal::Format("%.*g", digits, x); }

std::string AxisName(int axis) { return std::string(1, static_cast<char>('x' + axis)); }

GyroMotion SamplesOf(const RawLog& accel, const RawLog& gyro, const std::vector<double>& t,
                     const ModelParameters& accel_params, Vec3 f0, std::size_t first,
                     std::size_t last) {
  GyroMotion motion;
  const std::size_t n = last + 1 - first;
  motion.t_s.reserve(n);
  motion.raw.reserve(n);
  motion.f.reserve(n);
  for (std::size_t k = first; k <= last; ++k) {
    motion.t_s.push_back(t[k]);
    motion.raw.push_back(gyro.samples[k]);
    if (std::optional<Vec3> f = SpecificForce(accel_params, accel.samples[k])) f0 = *f;
    motion.f.push_back(f0);
  }
  return motion;
}

Built BuildData(const RawLog& accel, const RawLog& gyro, const std::vector<Position>& positions,
                const CalibrationResult& accel_cal, const GyroCalibrationOptions& options) {
  Built b;
  GyroFitData& data = b.data;
  data.rule = options.rule;
  if (options.latitude_deg) {
    if (!(std::abs(*options.latitude_deg) <= 90)) {
      throw std::invalid_argument("CalibrateGyro: the latitude must lie in [-90, 90] deg");
    }
    data.earth_rate_vertical = kEarthRate_rad_s * std::sin(*options.latitude_deg * kPi / 180);
  }
  const std::size_t m = positions.size();
  if (accel_cal.directions.size() != m) {
    throw std::invalid_argument("CalibrateGyro: " + std::to_string(m) + " positions and " +
                                std::to_string(accel_cal.directions.size()) + " directions");
  }
  CheckPositions(positions, gyro);
  const Vec3 quantum = Quantum(gyro.samples);
  const double typical_step = gyro.time      ? gyro.time->typical_step_s
                              : accel.time   ? accel.time->typical_step_s
                              : gyro.rate_hz ? 1.0 / *gyro.rate_hz
                                             : 0.0;
  b.step_s = typical_step;
  // Where the gyro is still inside each position's interval (gyro_still_runs.hpp): the still
  // rates are averaged there, and the turns integrated from one run to the next.
  if (m == 0) throw DataError("no still positions: the gyroscope has no turns between them");
  std::vector<StaticInterval> intervals;
  for (const Position& p : positions) intervals.push_back(*p.interval);
  const internal::GyroStillRuns still =
      internal::FindGyroStillRuns(gyro.samples, intervals, typical_step, quantum);
  // The positions where the gyro stood still. One it turned throughout (about the vertical, which
  // the accelerometer cannot see) gives no still rate: the turns on either side of it are
  // integrated as one through it. Most of them turning is not a unit turned about the vertical:
  // the rates are not this accelerometer's, or the streams are out of step.
  std::vector<std::size_t> standing;
  for (std::size_t i = 0; i < m; ++i) {
    if (still.runs[i].end - still.runs[i].begin >= 2) standing.push_back(i);
  }
  if (2 * standing.size() < m || standing.size() < 2) {
    std::size_t first = 0;  // the first position without a still span (one position: itself)
    while (first + 1 < m && still.runs[first].end - still.runs[first].begin >= 2) ++first;
    throw DataError("the gyroscope turns throughout " + std::to_string(m - standing.size()) +
                    " of the " + std::to_string(m) + " still positions (position " +
                    std::to_string(first + 1) + ": lines " + LineOf(gyro, intervals[first].begin) +
                    "-" + LineOf(gyro, intervals[first].end - 1) + " of " + gyro.source +
                    "), where the accelerometer is still: these are not this accelerometer's "
                    "rates, or the two streams are far out of step");
  }
  b.still_runs = still.runs;
  StillRates(gyro, still, standing, accel_cal, quantum, &data);
  // The turns: from the last still sample of one position to the first of the next.
  b.t = IntegrationTimes(gyro, accel);
  const std::vector<double>& t = b.t;
  const Saturation saturation(gyro.samples, quantum, data.noise_sigma_raw);
  // The samples of a still span a turn's mean orientation is taken over (below), and whether a
  // span wobbles enough for it.
  const auto span = static_cast<std::size_t>(
      typical_step > 0 ? std::max(2.0, std::round(kMeanOrientationSpan_s / typical_step)) : 2.0);
  const auto wobbles = [&](std::size_t p) { return still.wobbles[p] != 0; };
  for (std::size_t j = 0; j + 1 < standing.size(); ++j) {
    const std::size_t i = standing[j], next = standing[j + 1];
    // The turn proper: from the last still sample of one position to the first of the next.
    const std::size_t first = still.runs[i].end - 1;
    const std::size_t last = still.runs[next].begin;
    // Integrated from the mean orientation over the end of the first still span to that over
    // the start of the next, which is what the accelerometer's mean readings see (a unit that
    // wobbles as it stands is not where it was on average at the span's last sample): the
    // span's steps weighted by the share of its samples before them, (k − b + 1)/n, those of the
    // next span by the share after them, each span's mean rotation taken to first order (a
    // wobble of a fraction of a degree). At most kMeanOrientationSpan_s of each span: over a
    // whole span the rates would integrate the Earth's unmodelled horizontal rate and the bias's
    // drift too (the Xsens's first span of 51 s turned its turn by 0.1°). Only a span that
    // wobbles (GyroStillRuns::wobbles) is averaged so: its samples' noise is in its still mean
    // too, and a quiet span's would make the two correlated for nothing (σ of b_g 15 % low over
    // 400 simulated recordings).
    StaticInterval from = still.runs[i], to = still.runs[next];
    from.begin = !wobbles(i) ? first : std::max(from.begin, from.end > span ? from.end - span : 0);
    to.end = !wobbles(next) ? last + 1 : std::min(to.end, to.begin + span);
    GyroMotion motion =
        SamplesOf(accel, gyro, t, accel_cal.params, accel_cal.gravity * accel_cal.directions[i],
                  from.begin, to.end - 1);
    if (wobbles(i) || wobbles(next)) motion.step_weight.assign(motion.t_s.size() - 1, 1.0);
    const auto n_from = static_cast<double>(from.end - from.begin);
    const auto n_to = static_cast<double>(to.end - to.begin);
    for (std::size_t k = from.begin; k + 1 < from.end; ++k) {
      motion.step_weight[k - from.begin] = static_cast<double>(k - from.begin + 1) / n_from;
    }
    for (std::size_t k = to.begin; k + 1 < to.end; ++k) {
      motion.step_weight[k - from.begin] = static_cast<double>(to.end - 1 - k) / n_to;
    }
    motion.from = i;
    motion.to = next;
    for (std::size_t k = first + 1; k <= last; ++k) {
      if (typical_step > 0 && t[k] - t[k - 1] > 5 * typical_step) {
        throw DataError("the turn from position " + std::to_string(i + 1) + " to " +
                        std::to_string(next + 1) + " has a gap of " + Num(t[k] - t[k - 1], 4) +
                        " s in its samples (at line " +
                        std::to_string(gyro.line.empty() ? k + 1 : gyro.line[k]) + " of " +
                        gyro.source + "): its rotation cannot be integrated");
      }
    }
    saturation.Refuse(gyro, first, last, i, next);
    GyroRotation r;
    r.from = i;
    r.to = next;
    r.first_sample = first;
    r.last_sample = last;
    r.duration_s = t[last] - t[first];
    b.rotations.push_back(r);
    data.motions.push_back(std::move(motion));
  }
  return b;
}

}  // namespace internal

// The two streams must be one clock: a gyro sample at each accelerometer sample's time.
void CheckGyroClock(const RawLog& accel, const RawLog& gyro) {
  if (gyro.samples.size() != accel.samples.size()) {
    throw DataError("the gyroscope's log " + gyro.source + " has " +
                    std::to_string(gyro.samples.size()) + " samples and the accelerometer's " +
                    std::to_string(accel.samples.size()) +
                    ": the two streams must be on one clock, a rate sample at each "
                    "accelerometer sample's time");
  }
  if (gyro.samples == accel.samples) {
    throw DataError("the gyroscope's readings in " + gyro.source +
                    " are the accelerometer's, value for value: its columns or its file are the "
                    "accelerometer's");
  }
  if (gyro.time_s.empty() || accel.time_s.empty()) return;  // same rows of one file
  const double step = accel.time ? accel.time->typical_step_s : 0.0;
  const double origin_offset =
      (gyro.time ? gyro.time->origin_s : 0.0) - (accel.time ? accel.time->origin_s : 0.0);
  for (std::size_t k = 0; k < gyro.time_s.size(); ++k) {
    const double d = gyro.time_s[k] + origin_offset - accel.time_s[k];
    if (!(std::abs(d) <= 0.5 * step)) {
      throw DataError("the gyroscope's sample " + std::to_string(k + 1) + " (line " +
                      std::to_string(gyro.line.empty() ? k + 1 : gyro.line[k]) + " of " +
                      gyro.source + ") is " + Num(d, 6) +
                      " s from the accelerometer's: the two streams must be on one clock");
    }
  }
}

}  // namespace accelcal
