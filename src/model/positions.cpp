#include "accelcal/positions.hpp"

#include <cmath>

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
    p.temperature_c = interval.temperature_c;
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

std::vector<Vec3> SigmasOfMeans(const std::vector<Position>& positions) {
  std::vector<Vec3> sigmas;
  for (const Position& p : positions) {
    if (!p.std || p.samples < 2 || !p.std->allFinite() || !(p.std->minCoeff() > 0)) return {};
    sigmas.push_back(*p.std / std::sqrt(static_cast<double>(p.samples)));
  }
  return sigmas;
}

}  // namespace accelcal
