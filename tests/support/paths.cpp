// The paths of support/paths.hpp, given by tests/CMakeLists.txt to this file alone.
#include "support/paths.hpp"

namespace accelcal::test {
const char* DataDirectory() { return ACCELCAL_TESTS_DATA_DIR; }
const char* SourceDirectory() { return ACCELCAL_TESTS_SOURCE_DIR; }
const char* CliPath() { return ACCELCAL_TESTS_CLI; }
}  // namespace accelcal::test
