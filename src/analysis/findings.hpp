#pragma once
// A finding added as the diagnosis states them (diagnosis.cpp, gyro_findings.cpp).
#include <string>
#include <utility>
#include <vector>

#include "accelcal/diagnosis.hpp"

namespace accelcal::internal {

inline void AddFinding(std::vector<Finding>* out, const char* code, Severity severity,
                       std::string message,
                       std::vector<std::pair<std::string, double>> numbers = {}) {
  out->push_back({code, severity, std::move(message), std::move(numbers)});
}

}  // namespace accelcal::internal
