// The detection kernels (io/detection_kernels.hpp) do the Eigen 3-vector operations they replaced,
// lane by lane in the same order: both builds (AVX and baseline) must give the bits of those
// operations written out with Eigen, whatever CPU runs the tests.
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/cpu_features.hpp"
#include "io/detection_kernels.hpp"

namespace accelcal {
namespace {

namespace dk = internal::detection;

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A still log with noise, raw counts far from zero (quantised to whole counts) and a turn.
std::vector<Vec3> Samples(std::size_t n, bool quantised, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<Vec3> s(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double turn = i > n / 2 && i < n / 2 + 50 ? 400.0 * std::sin(0.1 * double(i)) : 0.0;
    for (int a = 0; a < 3; ++a) {
      double v = 33000.0 + 1000.0 * a + turn + noise(rng);
      s[i](a) = quantised ? std::round(v) : v;
    }
  }
  return s;
}

// Each kernel on every build this CPU can run.
template <typename Kernel>
std::vector<typename Kernel::Args> OnEveryBuild(const typename Kernel::Args& args) {
  std::vector<typename Kernel::Args> out;
  typename Kernel::Args baseline = args;
  dk::RunOnBaseline<Kernel>(baseline);
  out.push_back(baseline);
#if defined(__x86_64__)
  if (internal::Cpu().avx) {
    typename Kernel::Args avx = args;
    dk::RunOnAvx<Kernel>(avx);
    out.push_back(avx);
  }
#endif
  return out;
}

TEST(DetectionKernels, SmallestStepsAreEigensOnEveryBuild) {
  for (const bool quantised : {false, true}) {
    const std::vector<Vec3> s = Samples(1001, quantised, 3);
    Vec3 expected = Vec3::Constant(INFINITY);
    for (std::size_t i = 1; i < s.size(); ++i) {
      const Vec3 d = (s[i] - s[i - 1]).cwiseAbs();
      for (int a = 0; a < 3; ++a) {
        if (d(a) > 0 && d(a) < expected(a)) expected(a) = d(a);
      }
    }
    for (const dk::SmallestSteps& got : OnEveryBuild<dk::FindSmallestSteps>({&s, Vec3::Zero()})) {
      for (int a = 0; a < 3; ++a) EXPECT_TRUE(SameBits(got.step(a), expected(a))) << a;
    }
    if (quantised) {
      EXPECT_EQ(expected, Vec3::Ones());
    }
  }
  const std::vector<Vec3> constant(5, Vec3(1, 2, 3));  // no step at all: infinity
  for (const dk::SmallestSteps& got :
       OnEveryBuild<dk::FindSmallestSteps>({&constant, Vec3::Zero()})) {
    EXPECT_TRUE(std::isinf(got.step(0)) && std::isinf(got.step(1)) && std::isinf(got.step(2)));
  }
}

TEST(DetectionKernels, SlidingWindowScoresAreEigensOnEveryBuild) {
  const std::size_t n = 700, w = 51, h = w / 2, begin = 100, end = 650;
  const std::vector<Vec3> s = Samples(n, false, 5);
  const double wn = double(w), ratio = 4.0, floor = 0.2;
  // The first window's sums, then the slide, as DetectStaticIntervals wrote them with Eigen.
  const Vec3 shift = s[begin];
  Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero(), dsum = Vec3::Zero(), dsum2 = Vec3::Zero();
  for (std::size_t i = begin; i < begin + w; ++i) {
    sum += s[i] - shift;
    sum2 += (s[i] - shift).cwiseAbs2();
    if (i > begin) {
      dsum += s[i] - s[i - 1];
      dsum2 += (s[i] - s[i - 1]).cwiseAbs2();
    }
  }
  std::vector<double> score(n, std::nan(""));
  std::vector<char> white(n, 0);
  {
    Vec3 a = sum, a2 = sum2, d = dsum, d2 = dsum2;
    for (std::size_t c = begin + h;; ++c) {
      const Vec3 var = (a2 - a.cwiseAbs2() / wn) / (wn - 1);
      const Vec3 dvar = (d2 - d.cwiseAbs2() / (wn - 1)) / (wn - 2);
      score[c] = var.cwiseMax(0.0).sum();
      white[c] = score[c] <= ratio * std::max(0.5 * dvar.cwiseMax(0.0).sum(), floor);
      if (c + h + 1 >= end) break;
      const Vec3 out = s[c - h] - shift, in = s[c + h + 1] - shift;
      a += in - out;
      a2 += in.cwiseAbs2() - out.cwiseAbs2();
      const Vec3 dout = s[c - h + 1] - s[c - h], din = s[c + h + 1] - s[c + h];
      d += din - dout;
      d2 += din.cwiseAbs2() - dout.cwiseAbs2();
    }
  }
  std::size_t builds = 0;
  std::vector<double> got_score(n, std::nan(""));
  std::vector<char> got_white(n, 0);
  const dk::WindowSums args{s.data(), begin, end,   h,     shift,   sum,     sum2, dsum,
                            dsum2,    wn,    ratio, floor, nullptr, nullptr, 0};
  for (int build = 0; build < 2; ++build) {
    std::fill(got_score.begin(), got_score.end(), std::nan(""));
    std::fill(got_white.begin(), got_white.end(), 0);
    dk::WindowSums io = args;
    io.score = got_score.data();
    io.white = got_white.data();
    if (build == 0) {
      dk::RunOnBaseline<dk::SlideWindows>(io);
    } else {
#if defined(__x86_64__)
      if (!internal::Cpu().avx) continue;
      dk::RunOnAvx<dk::SlideWindows>(io);
#else
      continue;
#endif
    }
    ++builds;
    EXPECT_EQ(io.valid, end - begin - 2 * h);
    int differing = 0, quiet = 0;
    for (std::size_t c = 0; c < n; ++c) {
      differing += !SameBits(got_score[c], score[c]) || got_white[c] != white[c];
      quiet += got_white[c];
    }
    EXPECT_EQ(differing, 0) << "build " << build;
    EXPECT_GT(quiet, 0);  // both outcomes occur
    EXPECT_LT(quiet, int(end - begin - 2 * h));
  }
  EXPECT_GE(builds, 1u);
}

TEST(DetectionKernels, ExtremeCountsAreEigensOnEveryBuild) {
  const std::vector<Vec3> s = Samples(2000, true, 7);
  Vec3 largest = s[0], smallest = s[0];
  for (const Vec3& x : s) largest = largest.cwiseMax(x), smallest = smallest.cwiseMin(x);
  const std::size_t begin = 900, end = 1100;  // holds the turn's extremes
  std::size_t expected[3][2] = {};
  for (std::size_t i = begin; i < end; ++i) {
    for (int a = 0; a < 3; ++a) {
      expected[a][0] += s[i](a) == largest(a);
      expected[a][1] += s[i](a) == smallest(a);
    }
  }
  EXPECT_GT(expected[0][0] + expected[0][1], 0u);
  for (const dk::ExtremeCounts& got :
       OnEveryBuild<dk::CountExtremes>({s.data(), begin, end, largest, smallest, {}})) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(got.at[a][0], expected[a][0]) << a;
      EXPECT_EQ(got.at[a][1], expected[a][1]) << a;
    }
  }
}

}  // namespace
}  // namespace accelcal
