#include "accelcal/version.hpp"

namespace accelcal {

std::string_view Version() { return ACCELCAL_VERSION; }  // from CMakeLists.txt's project()

}  // namespace accelcal
