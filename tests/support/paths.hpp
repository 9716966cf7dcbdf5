#pragma once
// Where the tests find the project's data, its sources and the command-line tool. The absolute
// paths are compiled into one translation unit (paths.cpp) only, so that every other test's
// object is the same whatever directory the tree was cloned to: a compiler cache reuses them
// (scripts/compiler-cache.sh).

namespace accelcal::test {
const char* DataDirectory();    ///< the project's data/
const char* SourceDirectory();  ///< the project's root
const char* CliPath();          ///< the accelcal executable under test
}  // namespace accelcal::test

#define ACCELCAL_DATA_DIR (::accelcal::test::DataDirectory())
#define ACCELCAL_SOURCE_DIR (::accelcal::test::SourceDirectory())
#define ACCELCAL_CLI (::accelcal::test::CliPath())
