// The one generalised ESD loop (statistics/screening.hpp) that both fits' screenings run: which
// steps are discordant and which the policy excludes, from the significance of each step alone.
#include <vector>

#include <gtest/gtest.h>

#include "statistics/screening.hpp"

namespace accelcal::internal {
namespace {

// Steps of the given significances (positions 10, 11, ...), ending after them.
EsdOutcome Steps(const std::vector<bool>& significant, OutlierPolicy policy, int max_excluded,
                 std::size_t* calls) {
  OutlierOptions options;
  options.policy = policy;
  options.max_excluded = max_excluded;
  *calls = 0;
  return GeneralisedEsd(options, [&](std::size_t step) -> std::optional<EsdStep> {
    ++*calls;
    EXPECT_EQ(step, *calls - 1);
    if (step >= significant.size()) return std::nullopt;
    EsdStep s;
    s.finding.position = static_cast<int>(10 + step);
    s.significant = significant[step];
    return s;
  });
}

TEST(GeneralisedEsd, DiscordantUpToTheLastSignificantStep) {
  std::size_t calls = 0;
  // Masking: the first step is not significant on its own, the second is: both are discordant.
  EsdOutcome o = Steps({false, true, false}, OutlierPolicy::kExclude, 3, &calls);
  EXPECT_EQ(calls, 3u);
  EXPECT_EQ(o.steps.size(), 3u);
  EXPECT_EQ(o.discordant, 2u);
  EXPECT_EQ(o.excluded, 2u);
  std::vector<OutlierFinding> f = DiscordantFindings(o);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0].position, 10);
  EXPECT_TRUE(f[0].excluded && f[1].excluded);
  // Flagging: the same findings, none excluded.
  o = Steps({false, true, false}, OutlierPolicy::kFlag, 3, &calls);
  EXPECT_EQ(o.discordant, 2u);
  EXPECT_EQ(o.excluded, 0u);
  EXPECT_FALSE(DiscordantFindings(o)[1].excluded);
  // At most max(1, max_excluded) steps; a limit of 0 still tests one step, excludes none.
  o = Steps({true, true, true, true}, OutlierPolicy::kExclude, 2, &calls);
  EXPECT_EQ(calls, 2u);
  EXPECT_EQ(o.discordant, 2u);
  EXPECT_EQ(o.excluded, 2u);
  o = Steps({true}, OutlierPolicy::kExclude, 0, &calls);
  EXPECT_EQ(calls, 1u);
  EXPECT_EQ(o.discordant, 1u);
  EXPECT_EQ(o.excluded, 0u);
  // A step that cannot run ends the procedure; nothing significant, nothing discordant.
  o = Steps({false, false}, OutlierPolicy::kExclude, 5, &calls);
  EXPECT_EQ(calls, 3u);
  EXPECT_EQ(o.discordant, 0u);
  EXPECT_TRUE(DiscordantFindings(o).empty());
}

}  // namespace
}  // namespace accelcal::internal
