// libFuzzer harness: the command line as a careless or hostile user types it. The input chooses
// a subcommand and up to 14 arguments: option names of every subcommand, values that options must
// check (negative, zero, NaN, infinities, beyond int, huge, empty, the wrong word), the names of
// real input files (copies in a scratch directory, which is the working directory: no argument
// can name anything outside it) and letters. The tool runs in-process (RunCommandLine). A finding
// is exit status 1 ("internal error": an exception the tool did not expect) or a crash; every
// other status is an answer. montecarlo is left out (its runs are minutes by design), and numbers
// come only from the list, so that no accepted option asks for hours of simulation.
// Run with -close_fd_mask=3 (the tool's stdout and stderr are not the fuzzer's) and corpus
// directories given as absolute paths (the harness works in its scratch directory).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"

namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kCommands = {"calibrate", "detect",       "compare", "apply",
                                            "export",    "report",       "design",  "simulate",
                                            "gimbal",    "system-level", "--help",  "--version"};

const std::vector<std::string> kOptions = {"--c-prefix",
                                           "--choose",
                                           "--columns",
                                           "--criterion",
                                           "--device",
                                           "--duration",
                                           "--estimator",
                                           "--fine",
                                           "--frame",
                                           "--gravity",
                                           "--height",
                                           "--init",
                                           "--init-rest",
                                           "--input-kind",
                                           "--instance",
                                           "--json",
                                           "--latitude",
                                           "--max-iterations",
                                           "--max-outliers",
                                           "--method",
                                           "--methods",
                                           "--min-static",
                                           "--model",
                                           "--noise",
                                           "--noise-density",
                                           "--orientations",
                                           "--outlier-probability",
                                           "--outliers",
                                           "-o",
                                           "--positions",
                                           "-q",
                                           "--rate",
                                           "--raw",
                                           "--raw-unit",
                                           "--raw-units",
                                           "--reference",
                                           "--report",
                                           "--residual-noise",
                                           "--runs",
                                           "--scenario",
                                           "--seed",
                                           "--threads",
                                           "--threshold-factor",
                                           "--time-unit",
                                           "--to",
                                           "--transition",
                                           "--truth",
                                           "--units",
                                           "-v",
                                           "--window",
                                           "--no-crossval",
                                           "--positions-out"};

const std::vector<std::string> kValues = {
    // numbers an option must check
    "-1", "0", "-0", "0.5", "3", "9.81", "100", "1e9", "nan", "-nan", "inf", "-inf", "1e308",
    "-1e308", "1e-300", "2147483648", "21474837", "9223372036854775808", "0x10", "1,2", "",
    // words
    "-", "abc", "auto", "linear", "quadratic", "joint", "two-step", "newton-lagrange", "modulus",
    "ellipsoid", "raw", "positions", "g", "m/s2", "s", "ms", "us", "ns", "yaml", "px4", "ardupilot",
    "kalibr", "c-header", "imutk", "exclude", "keep", "off", "yang18", "six", "random:5",
    "random:-5", "random:1e9", "random:12:3", "yang2012", "sunxu2020", "wu2018-system", "x,y,z",
    "1,2,3", "t,x,y,z", "1,2,3,4", "0,1,2", "d", "a",
    // files (in the scratch directory)
    "log.mat", "pos.csv", "cal.json", "orient.csv", "out.json", "r.html", "out.csv", "missing", ".",
    "series.bin"};

bool g_ready = false;
std::string g_scratch;

void RemoveScratch() {
  std::error_code ignored;
  fs::remove_all(g_scratch, ignored);
}

int Run(std::vector<std::string> args) {
  args.insert(args.begin(), "accelcal");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return accelcal::cli::RunCommandLine(static_cast<int>(args.size()), argv.data());
}

void Prepare() {
  const fs::path data = fs::path(ACCELCAL_SOURCE_DIR) / "data";
  char scratch[] = "/tmp/accelcal_fuzz_cli_XXXXXX";
  if (::mkdtemp(scratch) == nullptr || ::chdir(scratch) != 0) std::abort();
  g_scratch = scratch;
  std::atexit(RemoveScratch);
  fs::copy_file(data / "imutk-xsens-mti/xsens_acc.mat", "log.mat");
  fs::copy_file(data / "imutk-xsens-mti/derived_static_means.csv", "pos.csv");
  fs::copy_file(data / "imucal-ferraris/ferraris_orientations.csv", "orient.csv");
  if (Run({"calibrate", "log.mat", "--gravity", "9.81744", "-q", "-o", "cal.json"}) != 0 ||
      Run({"simulate", "--scenario", "wu2018-system", "--duration", "20", "-o", "series.bin"}) !=
          0) {
    std::abort();
  }
  g_ready = true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (!g_ready) Prepare();
  if (size == 0) return 0;
  std::vector<std::string> args = {kCommands[data[0] % kCommands.size()]};
  for (std::size_t i = 1; i < size && args.size() < 15; ++i) {
    const std::uint8_t b = data[i];
    if (b < 112) {
      args.push_back(kOptions[b % kOptions.size()]);
    } else if (b < 240) {
      args.push_back(kValues[b % kValues.size()]);
    } else {  // letters only: no path out of the scratch directory, no number beyond the list
      std::string word;
      for (std::size_t n = b - 239u; n > 0 && i + 1 < size; --n) {
        word += static_cast<char>('a' + data[++i] % 26);
      }
      args.push_back(word);
    }
  }
  const int status = Run(args);
  if (status == accelcal::cli::kExitInternal || status < 0 || status > 6) {
    std::fprintf(stderr, "exit status %d from:", status);
    for (const std::string& a : args) std::fprintf(stderr, " '%s'", a.c_str());
    std::fprintf(stderr, "\n");
    std::abort();
  }
  // The inputs stay as they were: the next run starts from the same files.
  return 0;
}
