// Inputs read in bounded memory whatever they are (issue 16): a log read from a file in blocks
// gives exactly what the same text in memory gives; a file that shrinks while it is read is an
// error (it was a SIGBUS when the file was mapped); a pipe is read up to a limit; the line
// counter does not wrap.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/series_file.hpp"
#include "accelcal/sha256.hpp"
#include "io/text_lines.hpp"

namespace accelcal {
namespace {

std::string TempPath(const std::string& name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir ? dir : "/tmp") + "/accelcal_bounds_" + std::to_string(::getpid()) + "_" +
         name;
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string ErrorReading(const std::string& path, const ReadOptions& options) {
  try {
    ReadInput(path, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// Over 3 MiB with comments, blank lines, and a header, so that lines straddle the 1 MiB blocks.
std::string LongLog(const char* eol) {
  std::string text = std::string("# a comment") + eol + "t,x,y,z" + eol;
  for (int k = 0; k < 160000; ++k) {
    text += std::to_string(k) + "e-3," + std::to_string(k % 977) + ".25,-2," +
            std::to_string(k % 13) + eol;
    if (k % 1000 == 0) text += std::string(eol) + "  # note " + std::to_string(k) + eol;
  }
  return text;
}

TEST(InputBounds, AFileReadInBlocksGivesWhatTheTextInMemoryGives) {
  for (const char* eol : {"\n", "\r\n", "\r"}) {
    const std::string text = LongLog(eol);
    ASSERT_GT(text.size(), std::size_t{3} << 20);
    const std::string path = TempPath("blocks.csv");
    WriteText(path, text);
    ReadOptions options;
    options.fingerprint = true;
    const InputData from_file = ReadInput(path, options);
    const InputData in_memory = ParseInput(text, path, options);
    std::remove(path.c_str());
    // The blocks are hashed on a second thread while they are parsed: the digest of the whole
    // text, in order, all 13 blocks of it.
    EXPECT_EQ(from_file.bytes, text.size());
    EXPECT_EQ(from_file.sha256, Sha256Hex(text));
    ASSERT_EQ(from_file.kind, InputKind::kRaw);
    ASSERT_EQ(from_file.raw.samples.size(), 160000u);
    EXPECT_EQ(from_file.raw.samples, in_memory.raw.samples);
    EXPECT_EQ(from_file.raw.time_s, in_memory.raw.time_s);
    EXPECT_EQ(from_file.raw.line, in_memory.raw.line);
    // Line numbers count every line: 2 before the first row, 2 more every 1000 rows.
    EXPECT_EQ(from_file.raw.line[0], 3u);
    EXPECT_EQ(from_file.raw.line[1], 6u);
    EXPECT_EQ(from_file.raw.line.back(), 3u + 159999u + 2 * 160u);
  }
}

TEST(InputBounds, AnErrorDeepInAFileNamesItsLine) {
  std::string text = LongLog("\n");
  text += "1,2,x,4\n";
  const std::string path = TempPath("late_error.csv");
  WriteText(path, text);
  const std::string error = ErrorReading(path, {});
  std::remove(path.c_str());
  EXPECT_NE(error.find(":160323: column 3: 'x' is not a number"), std::string::npos) << error;
}

TEST(InputBounds, AFileThatShrinksWhileReadIsAnErrorNotACrash) {
  // The progress hook runs between blocks of rows: the file is cut there, as a logger rotating
  // it with copytruncate would. A mapped file raised SIGBUS past the new end.
  std::string text = "t,x,y,z\n";
  for (int k = 0; k < 400000; ++k) text += std::to_string(k) + "e-3,1.5,2.5,3.5\n";
  const std::string path = TempPath("shrinks.csv");
  WriteText(path, text);
  ReadOptions options;
  bool cut = false;
  options.progress = [&](std::size_t, std::size_t) {
    if (!cut) {
      ASSERT_EQ(::truncate(path.c_str(), 4096), 0);
    }
    cut = true;
  };
  const std::string error = ErrorReading(path, options);
  std::remove(path.c_str());
  EXPECT_TRUE(cut);
  EXPECT_NE(error.find("shrank while it was read"), std::string::npos) << error;
}

// A file of 400000 rows whose modification time is a day old, so that any write to it moves it.
std::string OldFile(const std::string& name, std::string* text) {
  *text = "t,x,y,z\n";
  for (int k = 0; k < 400000; ++k) *text += std::to_string(k) + "e-3,1.5,2.5,3.5\n";
  const std::string path = TempPath(name);
  WriteText(path, *text);
  struct stat st;
  EXPECT_EQ(::stat(path.c_str(), &st), 0);
  const struct timespec times[2] = {{st.st_mtim.tv_sec - 86400, 0}, {st.st_mtim.tv_sec - 86400, 0}};
  EXPECT_EQ(::utimensat(AT_FDCWD, path.c_str(), times, 0), 0);
  return path;
}

TEST(InputBounds, AFileWrittenToWhileReadIsAnErrorWhenItsDigestIsTaken) {
  // Bytes rewritten in place (the size unchanged) between blocks of rows: the parse and the
  // digest's own reading may each have seen either version, so neither is reported.
  std::string text;
  const std::string path = OldFile("rewritten.csv", &text);
  ReadOptions options;
  options.fingerprint = true;
  bool written = false;
  options.progress = [&](std::size_t, std::size_t) {
    if (written) return;
    written = true;
    const int fd = ::open(path.c_str(), O_WRONLY);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::pwrite(fd, "9", 1, 100), 1);
    ::close(fd);
  };
  const std::string error = ErrorReading(path, options);
  // Read again once nothing writes to it: its digest.
  ReadOptions again;
  again.fingerprint = true;
  const InputData data = ReadInput(path, again);
  std::string changed = text;
  changed[100] = '9';
  std::remove(path.c_str());
  EXPECT_TRUE(written);
  EXPECT_NE(error.find("the file changed while it was read (it was written to"), std::string::npos)
      << error;
  EXPECT_EQ(data.sha256, Sha256Hex(changed));
  EXPECT_EQ(data.bytes, changed.size());
}

TEST(InputBounds, AFileThatGrowsWhileReadIsAnErrorWhenItsDigestIsTaken) {
  // A logger still appending: what was read is the file as opened, but the digest, whose
  // provenance names the file, would describe something the file no longer is.
  std::string text;
  const std::string path = OldFile("grows.csv", &text);
  ReadOptions options;
  options.fingerprint = true;
  bool appended = false;
  options.progress = [&](std::size_t, std::size_t) {
    if (appended) return;
    appended = true;
    std::ofstream(path, std::ios::binary | std::ios::app) << "400000e-3,1.5,2.5,3.5\n";
  };
  const std::string error = ErrorReading(path, options);
  // Without a digest asked for, the file as it was when opened, as before.
  appended = true;
  ReadOptions plain;
  const InputData data = ReadInput(path, plain);
  std::remove(path.c_str());
  EXPECT_NE(error.find("changed while it was read (it grew from " + std::to_string(text.size()) +
                       " to " + std::to_string(text.size() + 22) + " bytes)"),
            std::string::npos)
      << error;
  EXPECT_EQ(data.raw.samples.size(), 400001u);
}

TEST(InputBounds, StandardInputPastItsStartIsHashedFromWhereItIsRead) {
  // A regular file as standard input, its first line already read by someone else: the digest
  // and the size are those of the bytes read from there (the reader used to take the file's whole
  // size for what was left, and called it shrunk).
  const std::string text = "t,x,y,z\n0,1,2,3\n0.01,1,2,3\n0.02,1,2,3\n";
  const std::string path = TempPath("stdin.csv");
  WriteText(path, text);
  const int saved = ::dup(STDIN_FILENO);
  const int fd = ::open(path.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::lseek(fd, 8, SEEK_SET), 8);  // past "t,x,y,z\n"
  ASSERT_EQ(::dup2(fd, STDIN_FILENO), STDIN_FILENO);
  ::close(fd);
  ReadOptions options;
  options.fingerprint = true;
  options.kind = InputKind::kRaw;
  std::string error;
  InputData data;
  try {
    data = ReadInput("-", options);
  } catch (const InputError& e) {
    error = e.what();
  }
  ::dup2(saved, STDIN_FILENO);
  ::close(saved);
  std::remove(path.c_str());
  ASSERT_EQ(error, "");
  EXPECT_EQ(data.bytes, text.size() - 8);
  EXPECT_EQ(data.sha256, Sha256Hex(text.substr(8)));
  EXPECT_EQ(data.raw.samples.size(), 3u);
}

TEST(InputBounds, APipeIsHashedAsItIsRead) {
  const std::string fifo = TempPath("hashed_pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string text = "t,x,y,z\n";
  for (int k = 0; k < 100000; ++k)
    text += std::to_string(k) + "e-2,1.5,2.5," + std::to_string(k % 7) + "\n";
  std::thread writer([&] {
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    if (fd < 0) return;
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t got = ::write(fd, text.data() + done, text.size() - done);
      if (got <= 0) break;
      done += static_cast<std::size_t>(got);
    }
    ::close(fd);
  });
  ReadOptions options;
  options.fingerprint = true;
  const InputData data = ReadInput(fifo, options);
  writer.join();
  std::remove(fifo.c_str());
  EXPECT_EQ(data.bytes, text.size());
  EXPECT_EQ(data.sha256, Sha256Hex(text));
  EXPECT_EQ(data.raw.samples.size(), 100000u);
}

TEST(InputBounds, ASeriesThatShrinksWhileReadIsAnErrorNotACrash) {
  for (const bool binary : {true, false}) {
    std::string text;
    if (binary) AppendSeriesHeader(&text);
    for (int k = 0; k < 300000; ++k) {
      SystemSample s;
      s.t = k * 1e-3;
      s.f = Vec3(0.1, 0.2, 9.8);
      if (binary) {
        AppendSeriesSample(s, &text);
      } else {
        text += std::to_string(s.t) + ",0.1,0.2,9.8,0,0\n";
      }
    }
    const std::string path = TempPath(binary ? "series.bin" : "series.csv");
    WriteText(path, text);
    long samples = 0;
    bool cut = false;
    std::string error = "no error";
    try {
      ReadSeries(
          path, [&](const SystemSample&) { ++samples; },
          [&](std::size_t done, std::size_t) {
            if (done > 0 && !cut) {
              ASSERT_EQ(::truncate(path.c_str(), 4096), 0);
              cut = true;
            }
          });
    } catch (const InputError& e) {
      error = e.what();
    }
    std::remove(path.c_str());
    EXPECT_TRUE(cut);
    EXPECT_LT(samples, 300000);
    EXPECT_NE(error.find("shrank while it was read"), std::string::npos) << error;
  }
}

TEST(InputBounds, APipeIsReadUpToTheStreamLimit) {
  const std::string fifo = TempPath("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::signal(SIGPIPE, SIG_IGN);  // the reader stops first; the writer's write then fails
  std::thread writer([&] {
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    if (fd < 0) return;
    const std::string row = "1.5,2.5,3.5\n";
    std::string chunk;
    for (int k = 0; k < 4096; ++k) chunk += row;
    for (int k = 0; k < 64; ++k) {  // 3 MiB, 1 MiB allowed
      if (::write(fd, chunk.data(), chunk.size()) < 0) break;
    }
    ::close(fd);
  });
  ReadOptions options;
  options.max_stream_bytes = std::size_t{1} << 20;
  const std::string error = ErrorReading(fifo, options);
  writer.join();
  std::remove(fifo.c_str());
  EXPECT_NE(error.find("more than 1 MiB from something that is not a regular file"),
            std::string::npos)
      << error;
}

TEST(InputBounds, DevicesAndDirectoriesAreRefusedAtOnce) {
  EXPECT_NE(ErrorReading("/dev/zero", {}).find("/dev/zero:1: a NUL byte at column 1"),
            std::string::npos);
  EXPECT_NE(ErrorReading("/dev/null", {}).find("no data"), std::string::npos);
  EXPECT_NE(ErrorReading("/", {}).find("is a directory"), std::string::npos);
}

// Issue 47: a name with a NUL is refused, not cut at the NUL (the system would have read the
// file whose name ends there, another file than the one named).
TEST(InputBounds, ANameWithANulIsRefused) {
  const std::string path = TempPath("nul");
  WriteText(path, "not this one\n");
  std::string error;
  try {
    ReadFileToString(path + std::string("\0.json", 6), 1 << 20);
  } catch (const InputError& e) {
    error = e.what();
  }
  std::remove(path.c_str());
  EXPECT_NE(error.find("nul\\x00.json: the name holds a NUL character"), std::string::npos)
      << error;
}

TEST(InputBounds, BlankLinesBeforeTheFirstRowAreBounded) {
  // 80 MiB of line ends: refused after 64 MiB, without holding the rest.
  const std::string path = TempPath("blank.csv");
  {
    std::ofstream out(path, std::ios::binary);
    const std::string blank(std::size_t{1} << 20, '\n');
    for (int k = 0; k < 80; ++k) out << blank;
    out << "1,2,3\n";
  }
  const std::string error = ErrorReading(path, {});
  std::remove(path.c_str());
  EXPECT_NE(error.find("only 0 data rows in the first 64 MiB"), std::string::npos) << error;
}

TEST(InputBounds, TheLineCounterStopsBeforeItWraps) {
  const std::string source = "huge.csv";
  internal::LineReader reader("1,2,3\n4,5,6\n", source, UINT32_MAX - 1, '\n');
  internal::Line line;
  ASSERT_TRUE(reader.Next(&line));
  EXPECT_EQ(line.number, UINT32_MAX);
  try {
    reader.Next(&line);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more than 4294967295 lines"), std::string::npos);
  }
}

}  // namespace
}  // namespace accelcal
