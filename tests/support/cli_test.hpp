#pragma once
// Runs the accelcal command as a user would, in a fresh directory per test: its exit status,
// stdout and stderr (test_cli.cpp, test_trust.cpp).
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/simulate.hpp"
#include "support/paths.hpp"

namespace accelcal::test {

namespace fs = std::filesystem;
inline const std::string kCli = ACCELCAL_CLI;

struct CliRun {
  int status;
  std::string out;  // stdout
  std::string err;  // stderr
};

inline std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("accelcal_cli_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name), std::ios::binary) << text;
    return Path(name);
  }
  CliRun Exec(const std::string& args) const {
    const std::string err = Path("stderr.txt");
    const std::string cmd = kCli + " " + args + " 2>" + err;
    CliRun r;
    FILE* pipe = popen(cmd.c_str(), "r");
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
    const int status = pclose(pipe);
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = Slurp(err);
    return r;
  }
  fs::path dir_;
};

// Readings as a positions file, x,y,z with every digit.
inline std::string ReadingsCsv(const std::vector<Vec3>& readings) {
  std::string s = "x,y,z\n";
  char line[128];
  for (const Vec3& p : readings) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", p(0), p(1), p(2));
    s += line;
  }
  return s;
}

// A positions file of `count` simulated readings of paper 000's device (9.8 m/s2, seed 2).
inline std::string PositionsCsv(int count) {
  return ReadingsCsv(SimulatePositions(Yang2012Truth(), 9.8, RandomDirections(count, 1),
                                       Vec3(0.05, 0.05, 0.05), 2));
}

}  // namespace accelcal::test
