#include "accelcal/positions.hpp"

namespace accelcal {

std::vector<Position> PositionsFromIntervals(const std::vector<StaticInterval>& intervals) {
  std::vector<Position> positions;
  positions.reserve(intervals.size());
  for (const StaticInterval& interval : intervals) {
    Position p;
    p.mean = interval.mean;
    p.samples = interval.count();
    p.std = interval.std;
    p.interval = interval;
    positions.push_back(p);
  }
  return positions;
}

std::vector<Vec3> Means(const std::vector<Position>& positions) {
  std::vector<Vec3> means;
  means.reserve(positions.size());
  for (const Position& p : positions) means.push_back(p.mean);
  return means;
}

}  // namespace accelcal
