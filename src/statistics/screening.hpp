#pragma once
// The generalised ESD procedure (Rosner 1983) of OutlierOptions, the one screening loop of both
// fits: the orientation-free calibration (outliers.cpp: Student t of the normal residuals) and
// the known-orientation fit (known_orientation.cpp: Fisher F of a position's three residuals).
// The most discordant position is removed and the rest refitted, max(1, max_excluded) times;
// each step is tested at its own level (false_alarm / positions in that fit); the discordant
// positions are the steps up to the last significant one (testing the later steps too is what
// finds two discordant positions that inflate the scatter enough to hide each other from the
// first), and the policy excludes up to max_excluded of them.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "accelcal/calibration_types.hpp"

namespace accelcal::internal {

/// A position whose leverage h_k leaves 1 − h_k at most this is not tested: the other positions
/// do not determine the fit without it (both fits' tests).
inline constexpr double kMinUntestedMargin = 1e-9;

/// One step: the most discordant position of a fit (in the caller's numbering), and whether it
/// is significant at that step's level.
struct EsdStep {
  OutlierFinding finding;
  bool significant = false;
};

struct EsdOutcome {
  std::vector<EsdStep> steps;  ///< every step tested, in order
  std::size_t discordant = 0;  ///< the steps up to the last significant one
  std::size_t excluded = 0;    ///< of those, the ones the policy leaves out
};

/// Runs the steps: `next(step)` fits the positions not removed yet (the caller removes the
/// previous step's position) and returns its most discordant one, or nothing when the test cannot
/// run or the fit fails (the procedure then ends).
EsdOutcome GeneralisedEsd(const OutlierOptions& options,
                          const std::function<std::optional<EsdStep>(std::size_t step)>& next);

/// The discordant steps' findings, the excluded ones marked.
std::vector<OutlierFinding> DiscordantFindings(const EsdOutcome& outcome);

}  // namespace accelcal::internal
