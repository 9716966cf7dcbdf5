// accelcal inspect: what a binary log holds (native_log.hpp).
#include "commands.hpp"

#include <algorithm>
#include <memory>
#include <string>

#include "accelcal/native_log.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {

using internal::VisibleLine;

int RunInspect(const InspectArgs& args) {
  const LogInventory log = InspectLog(args.path);
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["source"] = log.source;
    doc["format"] = ToString(log.format);
    doc["bytes"] = log.bytes;
    doc["truncated"] = log.truncated ? nlohmann::ordered_json(*log.truncated) : nullptr;
    doc["info"] = log.info;
    nlohmann::ordered_json& streams = doc["streams"] = nlohmann::ordered_json::array();
    for (const LogStreamInfo& s : log.streams) {
      streams.push_back(
          {{"topic", s.topic},
           {"type", s.type},
           {"instance", s.instance},
           {"device_id", s.device_id ? nlohmann::ordered_json(*s.device_id) : nullptr},
           {"frame_id", s.frame_id ? nlohmann::ordered_json(*s.frame_id) : nullptr},
           {"samples", s.samples},
           {"first_s", s.first_s},
           {"last_s", s.last_s},
           {"rate_hz", s.rate_hz > 0 ? nlohmann::ordered_json(s.rate_hz) : nullptr},
           {"sensors", s.sensors},
           {"unreadable", s.unreadable.empty() ? nlohmann::ordered_json(nullptr)
                                               : nlohmann::ordered_json(s.unreadable)}});
      if (s.frames.size() > 1) {
        nlohmann::ordered_json& frames = streams.back()["frames"] = nlohmann::ordered_json::array();
        for (const auto& [id, messages] : s.frames) {
          frames.push_back({{"frame_id", id}, {"messages", messages}});
        }
      }
    }
    doc["fields"] = log.fields;
    doc["parameters"] = log.parameters;
    nlohmann::ordered_json& changes = doc["parameter_changes"] = nlohmann::ordered_json::array();
    for (const LogInventory::ParameterChange& c : log.parameter_changes) {
      changes.push_back({{"name", c.name}, {"time_s", c.time_s}, {"value", c.value}});
    }
    out = JsonText(doc);
  } else {
    const char* format = log.format == LogFormat::kULog            ? "PX4 ULog"
                         : log.format == LogFormat::kDataFlash     ? "ArduPilot DataFlash"
                         : log.format == LogFormat::kRosBag        ? "ROS bag"
                         : log.format == LogFormat::kMcap          ? "MCAP"
                         : log.format == LogFormat::kRosbag2Sqlite ? "ROS 2 bag (SQLite)"
                                                                   : "MATLAB MAT-file";
    out += Format("%s: %s, %llu bytes\n", log.source.c_str(), format,
                  static_cast<unsigned long long>(log.bytes));
    for (const char* key : {"sys_name", "ver_hw", "ver_sw", "ver_sw_release"}) {
      if (const auto it = log.info.find(key); it != log.info.end()) {
        out += Format("%-10s%s\n", key, VisibleLine(it->second).c_str());
      }
    }
    if (log.truncated) out += "warning   " + VisibleLine(*log.truncated) + "\n";
    if (log.format == LogFormat::kMat) {
      // A MAT-file's variables; a numeric matrix is read as a text table.
      int width = 8;
      for (const LogStreamInfo& s : log.streams) {
        width = std::max(width, static_cast<int>(VisibleLine(s.topic).size()));
      }
      out += Format("%-*s %s\n", width, "variable", "size and class");
      std::size_t matrices = 0;
      for (const LogStreamInfo& s : log.streams) {
        const std::string what = !s.unreadable.empty()
                                     ? " (unreadable: " + VisibleLine(s.unreadable) + ")"
                                 : s.samples > 0 ? Format(" (%zu rows read)", s.samples)
                                                 : std::string();
        out += Format("%-*s %s%s\n", width, VisibleLine(s.topic).c_str(),
                      VisibleLine(s.type).c_str(), what.c_str());
        if (s.samples > 0 && s.unreadable.empty()) ++matrices;
      }
      out += Format(
          "%zu variables, %zu numeric matrices. A matrix is read as a text log's columns "
          "(--columns, --time-unit)%s\n",
          log.streams.size(), matrices, matrices > 1 ? "; choose one with --topic NAME" : "");
      WriteFileAtomically("-", out);
      return kExitOk;
    }
    // A ROS topic is named by its user, its type by ROS: both are shown.
    int width = 5, type_width = 0;
    for (const LogStreamInfo& s : log.streams) {
      width = std::max(width, static_cast<int>(VisibleLine(s.topic).size()));
      if (s.type != s.topic) {
        type_width = std::max(type_width, static_cast<int>(VisibleLine(s.type).size()));
      }
    }
    if (type_width > 0) type_width = std::max(type_width, 4);
    out += Format("%-*s %-*s%s%8s %10s %9s %10s %21s  %s\n", width, "topic", type_width,
                  type_width > 0 ? "type" : "", type_width > 0 ? " " : "", "instance", "device_id",
                  "samples", "rate [Hz]", "time [s]", "accelcal reads");
    for (const LogStreamInfo& s : log.streams) {
      std::string sensors;
      for (const std::string& k : s.sensors) sensors += (sensors.empty() ? "" : ", ") + k;
      out += Format("%-*s %-*s%s%8d %10s %9zu %10s %10.3f-%10.3f  %s\n", width,
                    VisibleLine(s.topic).c_str(), type_width,
                    type_width > 0 ? VisibleLine(s.type).c_str() : "", type_width > 0 ? " " : "",
                    s.instance, s.device_id ? std::to_string(*s.device_id).c_str() : "-", s.samples,
                    s.rate_hz > 0 ? Format("%.4g", s.rate_hz).c_str() : "-", s.first_s, s.last_s,
                    sensors.empty() ? "-" : sensors.c_str());
    }
    // What the table cannot say: a topic accelcal cannot decode, several sensors on one topic.
    for (const LogStreamInfo& s : log.streams) {
      if (!s.unreadable.empty()) {
        out += Format("topic %s: accelcal cannot decode its messages: %s\n",
                      VisibleLine(s.topic).c_str(), VisibleLine(s.unreadable).c_str());
      }
      if (s.frames.size() > 1) {
        std::string frames;
        for (const auto& [id, messages] : s.frames) {
          frames += Format("%s'%s' (%zu messages)", frames.empty() ? "" : ", ",
                           VisibleLine(id).c_str(), messages);
        }
        out += Format(
            "topic %s: its messages name %zu frames (header.frame_id), several sensors on one "
            "topic: %s; read one with --frame-id NAME\n",
            VisibleLine(s.topic).c_str(), s.frames.size(), frames.c_str());
      }
    }
    // A parameter set while the log ran: the values at the start are not the ones in force after.
    for (const LogInventory::ParameterChange& c : log.parameter_changes) {
      out += Format("parameter %s set to %.9g at %.6f s\n", VisibleLine(c.name).c_str(), c.value,
                    c.time_s);
    }
    out += Format(
        "%zu stream%s, %zu parameter%s. Read one with --topic NAME [--instance N]; one "
        "accelcal does not read by default with --columns naming its fields (--json lists "
        "them)\n",
        log.streams.size(), log.streams.size() == 1 ? "" : "s", log.parameters.size(),
        log.parameters.size() == 1 ? "" : "s");
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

CommandRun SetUpInspect(CLI::App* cmd) {
  auto a = std::make_shared<InspectArgs>();
  cmd->add_option("LOG", a->path, "binary log")->required();
  cmd->add_flag("--json", a->json, "machine-readable output");
  return [a](const CLI::App& /*parsed*/) {
    DataSubject() = a->path;
    return RunInspect(*a);
  };
}

}  // namespace accelcal::cli
