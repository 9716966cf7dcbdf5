// accelcal detect: the static intervals of a raw log.
#include "commands.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "accelcal/export.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {
int RunDetect(const DetectArgs& args) {
  InputArgs in = args.input;
  ReadOptions read = MakeReadOptions(in);
  read.kind = InputKind::kRaw;
  if (auto why = in.detection.Validate()) throw UsageError(*why);
  const InputData data = ReadInput(in.path, read);
  const StaticDetectionResult d = DetectStaticIntervals(data.raw, in.detection);
  if (d.intervals.empty()) throw NoStaticInterval(d);
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["source"] = in.path;
    doc["samples"] = data.raw.samples.size();
    doc["rate_hz"] = d.rate_hz;
    doc["window_samples"] = d.window_samples;
    doc["noise_reference"] = d.noise_reference;
    doc["threshold"] = d.threshold;
    if (const std::optional<TimeAxis>& t = data.raw.time) {
      doc["time"] = {
          {"unit", ToString(t->unit)}, {"origin_s", t->origin_s}, {"gaps", t->gaps.size()}};
    }
    if (!data.raw.temperature_source.empty()) doc["temperature"] = data.raw.temperature_source;
    nlohmann::ordered_json& intervals = doc["intervals"] = nlohmann::ordered_json::array();
    for (const StaticInterval& s : d.intervals) {
      intervals.push_back({{"begin", s.begin},
                           {"end", s.end},
                           {"samples", s.count()},
                           {"t_begin", s.t_begin_s},
                           {"t_end", s.t_end_s},
                           {"mean", JsonArray(s.mean)},
                           {"std", JsonArray(s.std)}});
      if (s.temperature_c) intervals.back()["temperature"] = *s.temperature_c;
    }
    out = JsonText(doc);
  } else {
    out += Format(
        "%s: %zu samples at %.6g Hz; window %zu samples; threshold %.4g raw^2 "
        "(noise reference %.4g)\n",
        in.path.c_str(), data.raw.samples.size(), d.rate_hz, d.window_samples, d.threshold,
        d.noise_reference);
    // What the time column was found to be, and the still periods not used (diagnosis.hpp).
    for (const Finding& f : LogFindings(&data.raw, &d)) out += "# " + VisibleLine(f.message) + "\n";
    const bool temperature = !data.raw.temperature_source.empty();
    if (temperature) {
      out += "# temperature [degC]: " + VisibleLine(data.raw.temperature_source) + "\n";
    }
    out += Format("%3s %9s %9s %11s %11s %8s %40s %33s%s\n", "#", "begin", "end", "t_begin",
                  "t_end", "samples", "mean", "std", temperature ? "  T[degC]" : "");
    for (std::size_t i = 0; i < d.intervals.size(); ++i) {
      const StaticInterval& s = d.intervals[i];
      out += Format("%3zu %9zu %9zu %11.4f %11.4f %8zu %s %s", i + 1, s.begin, s.end, s.t_begin_s,
                    s.t_end_s, s.count(), Vec(s.mean, "%13.7g ").c_str(),
                    Vec(s.std, "%10.4g ").c_str());
      if (temperature)
        out += s.temperature_c ? Format(" %8.3f", *s.temperature_c) : Format(" %8s", "-");
      out += "\n";
    }
    out += Format("%zu static intervals\n", d.intervals.size());
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

CommandRun SetUpDetect(CLI::App* cmd) {
  auto a = std::make_shared<DetectArgs>();
  cmd->add_option("LOG", a->input.path, "raw log")->required();
  AddInputOptions(cmd, &a->input, false);
  AddDetectionOptions(cmd, &a->input);
  cmd->add_flag("--json", a->json, "machine-readable output");
  return [a](const CLI::App& /*parsed*/) {
    DataSubject() = a->input.path;
    return RunDetect(*a);
  };
}

}  // namespace accelcal::cli
