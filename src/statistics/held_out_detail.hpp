#pragma once
// The pieces of the held-out validation (held_out.hpp) that its files share: what the held-out
// fits solve, the checks that send a position to a refit, and the ellipsoid method's own path.

#include <cstddef>
#include <vector>

#include "accelcal/calibration_types.hpp"
#include "solvers/solver_common.hpp"
#include "statistics/held_out.hpp"

namespace accelcal::internal::held_out {

// Cap of the foot point's Newton iteration (KktDirection); from the previous foot point it takes
// one or two steps.
inline constexpr int kFootPointIterations = 50;

enum class Objective { kProfiled, kModulusSquared, kModulusNorm };

// What the held-out fits solve, and the positions of the full fit in the x-first gauge.
struct Setup {
  Objective objective = Objective::kProfiled;
  bool bias_corrected = false;
  ModelKind model = ModelKind::kLinear;
  double gravity = 1;
  Vec12 mask;
  std::vector<Vec3> readings;  ///< the positions in the fit (x-first gauge)
  std::vector<Vec3> dirs;      ///< their foot points at the full fit (profiled objective)
  int dof_held_out = 0;        ///< m − 1 − P of a held-out fit
};

/// |f| − g of `reading` by `params`; NaN outside their range.
double HeldOutError(const ModelParameters& params, const Vec3& reading, double gravity);

// Whether the refit without position k might fail a check the expansion cannot see (CheckData's
// coplanarity, the observability of the model): those positions are refitted. The scatter of the
// other readings is the full scatter minus n/(n−1) (p_k − p̄)(p_k − p̄)ᵀ, whose smallest eigenvalue
// is at least the full one's minus n/(n−1) |p_k − p̄|².
struct Structure {
  Vec3 mean = Vec3::Zero();
  double lowest = 0, highest = 0;  // eigenvalues of the scatter
  double rcond = 0;                // of the full fit's information
  Mat12 S_inverse;
  Eigen::Matrix<double, Eigen::Dynamic, kMaxParameters> U;
};

Structure StructureOf(const Setup& setup, const ModelParameters& params,
                      const std::vector<Vec3>& dirs);
bool MayFailWithout(const Setup& setup, const Structure& s, std::size_t k);

// The held-out numbers of the iterative methods (fit positions' order); `refit` marks those a
// refit must give.
struct Candidates {
  std::vector<double> error;
  std::vector<bool> refit;
};

/// The ellipsoid method's held-out numbers (held_out_ellipsoid.cpp).
Candidates EllipsoidHeldOut(const Setup& setup, const ModelParameters& params, HeldOutPaths* paths);

}  // namespace accelcal::internal::held_out
