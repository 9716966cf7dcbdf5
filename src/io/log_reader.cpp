#include "accelcal/log_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>

#include "accelcal/error.hpp"
#include "accelcal/native_log.hpp"
#include "core/text_format.hpp"
#include "io/input_file.hpp"
#include "io/mat_file.hpp"
#include "io/native_input.hpp"
#include "io/number_parser.hpp"
#include "io/row_parser.hpp"
#include "io/text_lines.hpp"
#include "io/text_log.hpp"

namespace accelcal {

std::string_view ToString(InputKind kind) { return NameOf(kind); }

std::optional<InputKind> InputKindFromString(std::string_view text) {
  return FromName<InputKind>(text);
}

std::string ReadFileToString(const std::string& path, std::size_t max_bytes) {
  internal::InputFile file(path, max_bytes);
  const auto too_large = [&] {
    return InputError(
        file.name(), 0,
        "larger than " + std::to_string(max_bytes >> 20) + " MiB: not a file of this kind");
  };
  if (file.size() > max_bytes) throw too_large();
  // One allocation and one read for regular files; pipes and the like grow as they come (up to
  // `max_bytes`, InputFile's limit for them).
  std::string data(file.regular() ? file.size() : std::size_t{1} << 16, '\0');
  std::size_t used = file.ReadFully(data.data(), data.size());
  while (!file.regular() && used == data.size()) {
    data.resize(2 * data.size());
    used += file.ReadFully(data.data() + used, data.size() - used);
  }
  data.resize(used);
  return data;
}

namespace {

using internal::BlockColumns;
using internal::BlockSink;
using internal::kNoInstanceColumn;
using internal::ParseBlocks;
using internal::ShortNumber;

std::string TimeBackwards(double now, double before) {
  char buf[128];
  internal::FormatTo(buf, sizeof buf, "time goes backwards (%.9g after %.9g)", now, before);
  return buf;
}

// A recording that repeats each sample: the sample after each is an exact copy of it, the same
// time and the same values (a recorder, or a merge of a log with itself, that wrote every message
// twice). Read as it is, it has twice the samples at twice the rate, and its repeated timestamps
// look like a resolution coarser than the period. Refused when such copies are most of the steps
// (at least 40%; every sample twice gives 50%) and far more common (at least 4 times) than values
// repeated at distinct times: a still sensor quantised coarser than its noise repeats its values
// whatever the times, and timestamps coarser than the period come with values that differ.
constexpr double kMinCopiedSteps = 0.4;
constexpr double kCopiesOverRepeats = 4;
constexpr std::size_t kMinStepsForCopies = 16;

void RefuseCopiedSamples(const std::string& source, const std::vector<double>& t,
                         const std::vector<Vec3>& samples, const std::vector<std::uint32_t>& line) {
  if (t.size() != samples.size() || t.size() <= kMinStepsForCopies) return;
  std::size_t copies = 0, repeats = 0, first = 0;
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (samples[i] != samples[i - 1]) continue;
    if (t[i] == t[i - 1]) {
      if (copies++ == 0) first = i;
    } else {
      ++repeats;
    }
  }
  const double steps = static_cast<double>(t.size() - 1);
  if (static_cast<double>(copies) < kMinCopiedSteps * steps ||
      static_cast<double>(copies) < kCopiesOverRepeats * static_cast<double>(repeats)) {
    return;
  }
  throw InputError(
      source, line[first],
      internal::Format(
          "the recording repeats each sample: this sample is an exact copy of the one before "
          "it, the same time and values, as are %zu of its %zu samples (a recorder or a merge "
          "that wrote every message twice); read as it is, its rate and sample count would be "
          "twice the sensor's: keep one of each",
          copies, t.size()));
}

// The rate of a log with a time column: the timestamps', or the one given when it agrees with
// them within kRateTolerance (InputError otherwise).
double RateOf(const TimeAxis& time, const std::optional<double>& given, const std::string& source) {
  if (!given) return time.rate_hz;
  if (std::abs(*given / time.rate_hz - 1) > kRateTolerance) {
    throw InputError(source, 0,
                     "the given rate " + ShortNumber(*given) +
                         " Hz contradicts the time column, whose timestamps (" +
                         std::string(ToString(time.unit)) + ") come at " +
                         ShortNumber(time.rate_hz) + " Hz");
  }
  return *given;
}

// A topic names a stream of a binary log: a text file has none.
void RefuseTopicOfText(const std::string& source, const ReadOptions& options) {
  if (!options.topic.empty()) {
    throw InputError(source, 0,
                     "a topic was given, but this is a text file (its columns are chosen by "
                     "the columns option)");
  }
  if (!options.frame_id.empty()) {
    throw InputError(source, 0,
                     "a frame was given, but this is a text file: the frame option chooses among "
                     "a ROS topic's header.frame_id");
  }
}

// A MAT-file's matrix, read as the same numbers written as text would be (its rows the lines,
// each value in its shortest exact decimal form): every rule of a text log holds for it.
InputData ReadMat(internal::InputFile& file, const std::string& path, std::string head,
                  const ReadOptions& options) {
  if (!file.regular() || path == "-") {
    throw InputError(file.name(), 0,
                     "a MAT-file is read from its file (libmatio opens it by its path), not from "
                     "standard input, a pipe or a device");
  }
  if (!options.frame_id.empty()) {
    throw InputError(file.name(), 0,
                     "a frame was given, but this is a MAT-file: the frame option chooses among a "
                     "ROS topic's header.frame_id");
  }
  const internal::MatTable table = internal::ReadMatTable(path, options.topic);
  std::size_t row = 0, column = 0;
  std::string pending;  // what of the current value did not fit
  internal::TextBlocks blocks(
      [&](char* out, std::size_t n) {
        std::size_t done = 0;
        while (done < n) {
          if (pending.empty()) {
            if (row == table.rows) break;
            char value[32];
            const auto end = std::to_chars(value, value + sizeof value, table.At(row, column)).ptr;
            pending.assign(value, end);
            pending += ++column == table.columns ? '\n' : ',';
            if (column == table.columns) column = 0, ++row;
          }
          const std::size_t take = std::min(pending.size(), n - done);
          std::memcpy(out + done, pending.data(), take);
          pending.erase(0, take);
          done += take;
        }
        return done;
      },
      0);
  ReadOptions read = options;
  read.topic.clear();
  InputData data = ParseBlocks(blocks, file.name(), read);
  data.kind_reason = internal::Format(
      "MAT-file variable %s (%zu x %zu%s); %s", table.variable.c_str(),
      table.transposed ? table.columns : table.rows, table.transposed ? table.rows : table.columns,
      table.transposed ? ", its samples as columns: read turned" : "", data.kind_reason.c_str());
  if (options.fingerprint) {
    // The file's own bytes, as for any input.
    Sha256 hash;
    internal::BinaryStream in(&file, std::move(head));
    in.Fingerprint(&hash);
    in.Drain();
    internal::RequireUnchanged(file);
    data.bytes = in.offset();
    data.sha256 = hash.HexDigest();
  }
  return data;
}

// A binary input: a MAT-file's matrix, or a log's stream (ReadNativeLog).
InputData ReadBinary(internal::InputFile& file, const std::string& path, std::string head,
                     const ReadOptions& options) {
  if (DetectLogFormat(head) == LogFormat::kMat)
    return ReadMat(file, path, std::move(head), options);
  internal::BinaryStream in(&file, std::move(head));
  return internal::ReadNativeLog(in, &file, options, &path);
}

// A binary log keeps only the stream's samples (4 numbers each): read whole, one piece.
void StreamBinary(internal::InputFile& file, const std::string& path, std::string head,
                  const ReadOptions& read, const std::function<void(const RawLog& piece)>& sink,
                  StreamedLog* out) {
  const InputData data = ReadBinary(file, path, std::move(head), read);
  out->samples = data.raw.samples.size();
  out->rate_hz = data.raw.rate_hz;
  out->time = data.raw.time;
  out->read_warning = data.raw.read_warning;
  if (out->time) {
    for (const TimeGap& g : out->time->gaps) out->gap_lines.push_back(data.raw.line[g.index]);
  }
  sink(data.raw);
}

// The rows of the chosen instance (`instance_name` the file's instance column); without a
// choice, one value throughout (`instance_seen` the first, at `instance_seen_line`), else
// InputError.
void KeepInstance(const ReadOptions& options, const std::string& instance_name,
                  const std::string& source, const std::vector<double>& instances,
                  std::optional<double>* instance_seen, std::size_t* instance_seen_line,
                  RawLog* rows) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < rows->samples.size(); ++i) {
    const double v = instances[i];
    if (options.instance) {
      if (v != *options.instance) continue;
    } else if (!*instance_seen) {
      *instance_seen = v;
      *instance_seen_line = rows->line[i];
    } else if (v != **instance_seen) {
      throw InputError(source, rows->line[i],
                       "the rows belong to more than one sensor (instance column '" +
                           instance_name + "': " + ShortNumber(**instance_seen) + " from line " +
                           std::to_string(*instance_seen_line) + ", " + ShortNumber(v) +
                           " here): choose one instance");
    }
    if (!rows->time_s.empty()) rows->time_s[kept] = rows->time_s[i];
    rows->samples[kept] = rows->samples[i];
    rows->line[kept] = rows->line[i];
    ++kept;
  }
  if (!rows->time_s.empty()) rows->time_s.resize(kept);
  rows->samples.resize(kept);
  rows->line.resize(kept);
}

}  // namespace

void internal::FinishRawLog(RawLog* log, TimeUnit unit, const std::optional<double>& rate_hz,
                            std::string_view time_name) {
  const std::string& source = log->source;
  const std::vector<double>& t = log->time_s;
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (t[i] < t[i - 1]) throw InputError(source, log->line[i], TimeBackwards(t[i], t[i - 1]));
  }
  RefuseCopiedSamples(source, t, log->samples, log->line);
  if (log->time_s.size() >= 2) {
    try {
      log->time = MakeTimeAxis(&log->time_s, unit, time_name);
    } catch (const DataError& e) {
      throw InputError(source, 0, e.what());
    }
    log->rate_hz = RateOf(*log->time, rate_hz, source);
  } else if (log->time_s.size() == 1) {
    throw InputError(source, 0, "one sample: a raw log needs more");
  } else if (rate_hz) {
    log->rate_hz = rate_hz;
  }
}

InputData ParseInput(std::string_view text, const std::string& source, const ReadOptions& options) {
  if (DetectLogFormat(text.substr(0, 16)) == LogFormat::kMat) {
    throw InputError(source, 0,
                     "a MAT-file is read from its file (libmatio opens it by its path), not from "
                     "memory");
  }
  if (DetectLogFormat(text.substr(0, 16)) != LogFormat::kText) {
    internal::BinaryStream in(text, source, internal::BinaryStream::Borrowed{});
    return internal::ReadNativeLog(in, nullptr, options);
  }
  RefuseTopicOfText(source, options);
  internal::TextBlocks blocks(text);
  return ParseBlocks(blocks, source, options);
}

void internal::RequireUnchanged(const InputFile& file) {
  if (const std::optional<std::string> how = file.Changed()) {
    throw InputError(file.name(), 0,
                     "the file changed while it was read (it " + *how +
                         "): what was read may mix old and new bytes, and its SHA-256 would "
                         "not describe them; read it once nothing writes to it (a copy)");
  }
}

InputData ReadInput(const std::string& path, const ReadOptions& options) {
  internal::InputFile file(path, options.max_stream_bytes);
  // The first bytes tell a binary log from text.
  std::string head(16, '\0');
  head.resize(file.ReadFully(head.data(), head.size()));
  if (DetectLogFormat(head) != LogFormat::kText)
    return ReadBinary(file, path, std::move(head), options);
  RefuseTopicOfText(file.name(), options);
  Sha256 hash;
  internal::TextBlocks blocks(&file, std::move(head));
  if (options.fingerprint) blocks.Fingerprint(&hash);
  InputData data = ParseBlocks(blocks, file.name(), options);
  if (options.fingerprint) {
    for (std::string_view rest; blocks.Next(&rest);) {
    }  // the whole input is hashed, whatever the parser left
    blocks.FinishFingerprint();
    // The digest must describe the bytes parsed: a file written to meanwhile may have given the
    // parse some old bytes and some new.
    internal::RequireUnchanged(file);
    data.bytes = file.bytes_read();
    data.sha256 = hash.HexDigest();
  }
  return data;
}

StreamedLog StreamRawLog(const std::string& path, const ReadOptions& options,
                         const std::function<void(const RawLog& piece)>& sink) {
  internal::InputFile file(path, options.max_stream_bytes);
  ReadOptions read = options;
  read.kind = InputKind::kRaw;
  read.fingerprint = false;
  StreamedLog out;
  out.source = file.name();
  std::string head_bytes(16, '\0');
  head_bytes.resize(file.ReadFully(head_bytes.data(), head_bytes.size()));
  if (DetectLogFormat(head_bytes) != LogFormat::kText) {
    StreamBinary(file, path, std::move(head_bytes), read, sink, &out);
    return out;
  }
  RefuseTopicOfText(out.source, options);
  internal::TextBlocks blocks(&file, std::move(head_bytes));
  const std::string& source = out.source;
  BlockColumns columns;
  RawLog head;   // the first samples, their times as written, until the unit is decided
  RawLog piece;  // what goes to the sink
  piece.source = source;
  std::optional<TimeAxis> axis;
  double raw_t0 = 0, per_second = 1, typical = 0;
  double previous_raw = 0, previous_t = 0;
  double segment_t0 = 0, spans = 0, counted = 0;
  std::size_t segment_samples = 0;
  std::optional<double> instance_seen;
  std::size_t instance_seen_line = 0;
  // Converts rows of `rows` (times as written) to seconds, checks them and hands them on.
  const auto emit = [&](const RawLog& rows) {
    piece.time_s.clear();
    piece.samples.clear();
    piece.line.clear();
    for (std::size_t k = 0; k < rows.samples.size(); ++k) {
      if (axis) {
        const double v = rows.time_s[k];
        const double t = (v - raw_t0) / per_second;  // as MakeTimeAxis converts
        if (out.samples > 0) {
          if (v < previous_raw)
            throw InputError(source, rows.line[k], TimeBackwards(v, previous_raw));
          if (t - previous_t > kGapFactor * typical) {
            if (segment_samples >= 2) {
              spans += previous_t - segment_t0;
              counted += static_cast<double>(segment_samples - 1);
            }
            axis->gaps.push_back({out.samples, previous_t, t});
            out.gap_lines.push_back(rows.line[k]);
            segment_t0 = t;
            segment_samples = 0;
          }
        } else {
          segment_t0 = t;
        }
        previous_raw = v;
        previous_t = t;
        ++segment_samples;
        piece.time_s.push_back(t);
      }
      piece.samples.push_back(rows.samples[k]);
      piece.line.push_back(rows.line[k]);
      ++out.samples;
    }
    if (!piece.samples.empty()) sink(piece);
  };
  const auto decide = [&] {
    if (!columns.time || head.samples.empty()) return;
    if (head.samples.size() < 2) throw InputError(source, 0, "one sample: a raw log needs more");
    for (std::size_t i = 1; i < head.time_s.size(); ++i) {
      if (head.time_s[i] < head.time_s[i - 1]) {
        throw InputError(source, head.line[i], TimeBackwards(head.time_s[i], head.time_s[i - 1]));
      }
    }
    // Copies are found in the head: a recorder that writes every message twice does from the
    // start.
    RefuseCopiedSamples(source, head.time_s, head.samples, head.line);
    std::vector<double> times = head.time_s;
    try {
      axis = MakeTimeAxis(&times, options.time_unit, columns.time_name);
    } catch (const DataError& e) {
      throw InputError(source, 0, e.what());
    }
    axis->gaps.clear();  // found again over the whole log
    piece.time = axis;   // the head's unit, origin, typical step and resolution
    raw_t0 = head.time_s.front();
    per_second = UnitsPerSecond(axis->unit);
    typical = axis->typical_step_s;
  };
  bool decided = false;
  const BlockSink take = [&](InputData* data, std::vector<double>* instances) {
    RawLog& rows = data->raw;
    if (options.instance && columns.instance_name.empty()) {
      throw InputError(source, 0, kNoInstanceColumn);
    }
    if (!columns.instance_name.empty()) {
      KeepInstance(options, columns.instance_name, source, *instances, &instance_seen,
                   &instance_seen_line, &rows);
    }
    if (decided) {
      emit(rows);
    } else {
      head.time_s.insert(head.time_s.end(), rows.time_s.begin(), rows.time_s.end());
      head.samples.insert(head.samples.end(), rows.samples.begin(), rows.samples.end());
      head.line.insert(head.line.end(), rows.line.begin(), rows.line.end());
      if (head.samples.size() >= kStreamHeadSamples) {
        decide();
        decided = true;
        emit(head);
        head = RawLog();
      }
    }
    rows.time_s.clear();
    rows.samples.clear();
    rows.line.clear();
    instances->clear();
  };
  out.read_warning = ParseBlocks(blocks, source, read, &take, &columns).raw.read_warning;
  if (options.instance && columns.instance_name.empty()) {
    throw InputError(source, 0, kNoInstanceColumn);
  }
  if (!decided) {
    if (head.samples.empty()) {
      throw InputError(source, 0,
                       columns.instance_name.empty() || !options.instance
                           ? "a header but no data rows"
                           : "no rows of instance " + ShortNumber(*options.instance));
    }
    decide();
    emit(head);
  }
  if (axis) {
    if (segment_samples >= 2) {
      spans += previous_t - segment_t0;
      counted += static_cast<double>(segment_samples - 1);
    }
    if (!(spans > 0))
      throw InputError(source, 0, "the timestamps do not advance within any segment");
    axis->rate_hz = counted / spans;
    out.rate_hz = RateOf(*axis, options.rate_hz, source);
    out.time = std::move(axis);
  } else {
    if (out.samples == 1) throw InputError(source, 0, "one sample: a raw log needs more");
    out.rate_hz = options.rate_hz;
  }
  return out;
}

}  // namespace accelcal
