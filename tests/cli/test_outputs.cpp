// What the tool writes, and what it must never damage (issue 16): an output that names an input
// or another output is refused; two outputs are written together or not at all; a FIFO is
// written to, not replaced; a read-only file is left alone; a link planted at the old
// predictable temporary name redirects nothing; an interrupted run leaves no temporary file; a
// summary that cannot reach stdout is an error; options that ask for more than their limit are
// usage errors.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "support/cli_test.hpp"
#include "support/paths.hpp"

extern char** environ;

namespace accelcal::test {
namespace {

const std::string kXsens = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/xsens_acc.mat";

class Outputs : public CliTest {
 protected:
  // The directory's entries, hidden ones included.
  std::vector<std::string> Entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }
  std::string Calibration() {
    const CliRun r = Exec("calibrate " + kXsens + " --gravity 9.81744 -q -o " + Path("cal.json"));
    EXPECT_EQ(r.status, 0) << r.err;
    return Path("cal.json");
  }
};

TEST_F(Outputs, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  fs::copy_file(kXsens, Path("log.mat"));
  const std::string before = Slurp(Path("log.mat"));
  CliRun r = Exec("calibrate " + Path("log.mat") + " --gravity 9.81744 -o " + Path("log.mat"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("is the input"), std::string::npos) << r.err;
  EXPECT_EQ(Slurp(Path("log.mat")), before);
  // The same file by another name (a link) is the same file.
  fs::create_symlink(Path("log.mat"), Path("alias.mat"));
  r = Exec("calibrate " + Path("log.mat") + " --gravity 9.81744 --report " + Path("alias.mat"));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(Slurp(Path("log.mat")), before);
  const std::string cal = Calibration();
  const std::string cal_before = Slurp(cal);
  r = Exec("apply " + cal + " " + Path("log.mat") + " -o " + cal);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(Slurp(cal), cal_before);
  r = Exec("export " + cal + " --to yaml -o " + cal);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(Slurp(cal), cal_before);
}

TEST_F(Outputs, TwoOutputsAreWrittenTogetherOrNotAtAll) {
  CliRun r = Exec("calibrate " + kXsens + " --gravity 9.81744 -q -o " + Path("x.json") +
                  " --report " + Path("missing/r.html"));
  EXPECT_EQ(r.status, 5);
  EXPECT_NE(r.err.find("missing/r.html: cannot create a file in"), std::string::npos) << r.err;
  EXPECT_EQ(Entries(), std::vector<std::string>{"stderr.txt"});
  r = Exec("calibrate " + kXsens + " --gravity 9.81744 -q -o " + Path("f") + " --report " +
           Path("f"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("name the same file"), std::string::npos) << r.err;
  EXPECT_EQ(Entries(), std::vector<std::string>{"stderr.txt"});
  r = Exec("calibrate " + kXsens + " --gravity 9.81744 -q -o " + Path("x.json") + " --report " +
           Path("r.html"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Entries(), (std::vector<std::string>{"r.html", "stderr.txt", "x.json"}));
}

TEST_F(Outputs, AFifoIsWrittenToNotReplaced) {
  const std::string cal = Calibration();
  ASSERT_EQ(::mkfifo(Path("fifo").c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = Slurp(Path("fifo")); });
  const CliRun r = Exec("export " + cal + " --to yaml -q -o " + Path("fifo"));
  reader.join();
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(received.find("%YAML 1.2"), std::string::npos);
  EXPECT_TRUE(fs::is_fifo(Path("fifo")));
}

TEST_F(Outputs, AReadOnlyFileIsNotReplaced) {
  const std::string cal = Calibration();
  Write("ro.yaml", "keep me\n");
  ::chmod(Path("ro.yaml").c_str(), 0444);
  const CliRun r = Exec("export " + cal + " --to yaml -q -o " + Path("ro.yaml"));
  EXPECT_EQ(r.status, 5);
  EXPECT_NE(r.err.find("is read-only: not replaced"), std::string::npos) << r.err;
  EXPECT_EQ(Slurp(Path("ro.yaml")), "keep me\n");
}

TEST_F(Outputs, AReplacedFileKeepsItsModeAndALinkKeepsPointing) {
  const std::string cal = Calibration();
  Write("target.yaml", "old\n");
  ::chmod(Path("target.yaml").c_str(), 0640);
  fs::create_symlink("target.yaml", Path("link.yaml"));
  const CliRun r = Exec("export " + cal + " --to yaml -q -o " + Path("link.yaml"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(Path("link.yaml")));
  EXPECT_NE(Slurp(Path("target.yaml")).find("%YAML 1.2"), std::string::npos);
  struct stat st;
  ASSERT_EQ(::stat(Path("target.yaml").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  // A link to nothing is refused, not created through.
  fs::create_symlink("nowhere.yaml", Path("dangling.yaml"));
  EXPECT_EQ(Exec("export " + cal + " --to yaml -q -o " + Path("dangling.yaml")).status, 5);
  EXPECT_FALSE(fs::exists(Path("nowhere.yaml")));
}

TEST_F(Outputs, ALinkPlantedAtThePredictableTemporaryNameRedirectsNothing) {
  // The old writer opened OUT.tmp.<pid> with fopen("wb"), following a link planted there: links
  // for the next few thousand process ids, all to a file that must not change.
  const std::string cal = Calibration();
  Write("victim", "precious\n");
  const int pid = static_cast<int>(::getpid());
  for (int p = pid; p < pid + 1000; ++p) {
    fs::create_symlink(Path("victim"), Path("out.yaml.tmp." + std::to_string(p)));
  }
  const CliRun r = Exec("export " + cal + " --to yaml -q -o " + Path("out.yaml"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Slurp(Path("victim")), "precious\n");
  EXPECT_NE(Slurp(Path("out.yaml")).find("%YAML 1.2"), std::string::npos);
}

TEST_F(Outputs, ALongNameFitsWithItsTemporarySuffix) {
  const std::string cal = Calibration();
  const std::string name(250, 'n');
  const CliRun r = Exec("export " + cal + " --to yaml -q -o " + Path(name));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(Path(name)));
  EXPECT_EQ(Entries().size(), 3u);  // cal.json, the output, stderr.txt
}

TEST_F(Outputs, AnInterruptedRunLeavesNoTemporaryFile) {
  for (int sig : {SIGTERM, SIGINT}) {
    // A long raw simulation, streamed: interrupted once its temporary file has grown.
    const std::string out = Path("big.csv");
    std::vector<std::string> args = {kCli,    "simulate", "--scenario", "yang2012",
                                     "--raw", "--rate",   "1000",       "--duration",
                                     "3000",  "-o",       out};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t child = 0;
    ASSERT_EQ(::posix_spawn(&child, kCli.c_str(), nullptr, nullptr, argv.data(), environ), 0);
    bool growing = false;
    for (int wait = 0; wait < 3000 && !growing; ++wait) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      for (const auto& e : fs::directory_iterator(dir_)) {
        const std::string name = e.path().filename();
        growing |= name.rfind(".big.csv.", 0) == 0 && fs::file_size(e.path()) > (1 << 20);
      }
    }
    EXPECT_TRUE(growing);
    ::kill(child, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << status;
    EXPECT_TRUE(Entries().empty()) << Entries().front();
  }
}

TEST_F(Outputs, APathWithALineEndAddsNoLineToAppliedData) {
  const std::string cal = Calibration();
  const std::string evil = Path("cal\nx,y,z\n1,2,3.json");
  fs::copy_file(cal, evil);
  const CliRun r = Exec("apply '" + evil + "' " + kXsens + " -o " + Path("out.csv"));
  ASSERT_EQ(r.status, 0) << r.err;
  std::istringstream lines(Slurp(Path("out.csv")));
  std::string line;
  std::vector<std::string> head;
  while (head.size() < 3 && std::getline(lines, line)) head.push_back(line);
  ASSERT_EQ(head.size(), 3u);
  EXPECT_NE(head[0].find("# accelcal apply "), std::string::npos);
  EXPECT_NE(head[0].find("cal\\nx,y,z\\n1,2,3.json"), std::string::npos) << head[0];
  EXPECT_EQ(head[1].rfind("# time:", 0), 0u) << head[1];
  EXPECT_EQ(head[2], "time,x,y,z");
}

TEST_F(Outputs, ASummaryThatCannotBeWrittenIsAnError) {
  const CliRun r = Exec("calibrate " + kXsens + " --gravity 9.81744 > /dev/full");
  EXPECT_EQ(r.status, 5);
  EXPECT_NE(r.err.find("cannot write to stdout: No space left on device"), std::string::npos)
      << r.err;
}

TEST_F(Outputs, SimulationSizesAreCheckedBeforeAnythingIsMade) {
  CliRun r = Exec("simulate --scenario yang2012 --raw --duration 1e12 -o " + Path("x.csv"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("at most 100000000 are simulated"), std::string::npos) << r.err;
  r = Exec("simulate --scenario yang2012 --rate 1e12 -o " + Path("x.csv"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--rate must be a number of Hz in (0, 1e+06]"), std::string::npos) << r.err;
  r = Exec("simulate --scenario yang2012 --rate 10 --duration 0.01 -o " + Path("x.csv"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("1 to 2^53 samples per position"), std::string::npos) << r.err;
  r = Exec("simulate --scenario wu2018-system --duration 1e9 -o " + Path("x.bin"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("at most 100000000 are simulated"), std::string::npos) << r.err;
  EXPECT_EQ(Entries(), std::vector<std::string>{"stderr.txt"});
}

}  // namespace
}  // namespace accelcal::test
