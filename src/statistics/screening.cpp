#include "statistics/screening.hpp"

#include <algorithm>

namespace accelcal::internal {

EsdOutcome GeneralisedEsd(const OutlierOptions& options,
                          const std::function<std::optional<EsdStep>(std::size_t step)>& next) {
  EsdOutcome outcome;
  const auto max_steps = static_cast<std::size_t>(std::max(1, options.max_excluded));
  while (outcome.steps.size() < max_steps) {
    std::optional<EsdStep> step = next(outcome.steps.size());
    if (!step) break;
    outcome.steps.push_back(std::move(*step));
    if (outcome.steps.back().significant) outcome.discordant = outcome.steps.size();
  }
  if (options.policy == OutlierPolicy::kExclude) {
    outcome.excluded =
        std::min(outcome.discordant, static_cast<std::size_t>(std::max(0, options.max_excluded)));
  }
  return outcome;
}

std::vector<OutlierFinding> DiscordantFindings(const EsdOutcome& outcome) {
  std::vector<OutlierFinding> findings;
  for (std::size_t i = 0; i < outcome.discordant; ++i) {
    findings.push_back(outcome.steps[i].finding);
    findings.back().excluded = i < outcome.excluded;
  }
  return findings;
}

}  // namespace accelcal::internal
