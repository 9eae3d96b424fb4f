// sarmap-log info LOG: what a log holds, per channel, and where it is damaged.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "common/args.h"
#include "common/decode.h"
#include "common/node.h"
#include "common/sequence.h"
#include "common/time.h"
#include "log-tools/lcm_log_reader.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/image_t.hpp"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"

namespace {

using sarmap::logtools::LcmLogReader;
using sarmap::logtools::LogEvent;

struct ChannelSummary {
  std::map<std::string, int64_t> types;  // type name (or "?") -> count
  int64_t count = 0;
  int64_t bytes = 0;
  int64_t first_us = 0, last_us = 0;
  int64_t first_utime = 0, last_utime = 0;
  bool has_header = false;
  sarmap::common::PublisherSequences sequence;  // per publisher, as a node counts them
  std::string geometry;          // of the last message that has one
  bool geometry_varies = false;  // not the same in every message
};

// Who published a message, for the channels several publishers share (common::PublisherOf);
// "" otherwise.
std::string Publisher(const std::string& type, const std::vector<uint8_t>& data) {
  const auto of = [&](auto msg) {
    return sarmap::common::DecodeMessage(data.data(), data.size(), &msg)
               ? sarmap::common::PublisherOf(msg)
               : std::string();
  };
  if (type == "slam_anchor_request_t") return of(sarmap::slam_anchor_request_t());
  if (type == "node_status_t") return of(sarmap::node_status_t());
  if (type == "pm_info_t") return of(sarmap::pm_info_t());
  if (type == "pm_output_t") return of(sarmap::pm_output_t());
  return "";
}

// The sensor geometry of a message, for the types that have one; "" otherwise.
std::string Geometry(const std::string& type, const std::vector<uint8_t>& data) {
  char text[200];
  const auto decode = [&](auto* msg) {
    return sarmap::common::DecodeMessage(data.data(), data.size(), msg);
  };
  if (type == "laser_scan_t") {
    sarmap::laser_scan_t m;
    if (!decode(&m)) return "";
    const double to_deg = 180.0 / M_PI;
    snprintf(text, sizeof(text), "%d beams %.2f..%.2f deg step %.4f deg, %.2f-%.2f m%s",
             m.num_ranges, m.angle_min_rad * to_deg,
             (m.angle_min_rad + (m.num_ranges - 1) * m.angle_increment_rad) * to_deg,
             m.angle_increment_rad * to_deg, m.range_min_m, m.range_max_m,
             m.num_intensities ? ", intensities" : "");
  } else if (type == "image_t") {
    sarmap::image_t m;
    if (!decode(&m)) return "";
    const char* format = m.pixel_format == sarmap::image_t::PIXEL_DEPTH_U16 ? "depth u16"
                         : m.pixel_format == sarmap::image_t::PIXEL_GRAY8   ? "gray8"
                         : m.pixel_format == sarmap::image_t::PIXEL_RGB8    ? "rgb8"
                                                                            : "bgr8";
    const char* compression = m.compression == sarmap::image_t::COMPRESSION_JPEG  ? " jpeg"
                              : m.compression == sarmap::image_t::COMPRESSION_PNG ? " png"
                              : m.compression == sarmap::image_t::COMPRESSION_DEPTH_DELTA_ZSTD
                                  ? " zstd"
                                  : "";
    snprintf(text, sizeof(text), "%dx%d %s%s, fx %.1f fy %.1f cx %.1f cy %.1f", m.width, m.height,
             format, compression, m.intrinsics.fx, m.intrinsics.fy, m.intrinsics.cx,
             m.intrinsics.cy);
  } else if (type == "occupancy_grid_t") {
    sarmap::occupancy_grid_t m;
    if (!decode(&m)) return "";
    snprintf(text, sizeof(text), "%dx%d cells of %.3f m, origin (%.2f, %.2f) m", m.width, m.height,
             m.resolution_m, m.origin_x_m, m.origin_y_m);
  } else if (type == "audio_frame_t") {
    sarmap::audio_frame_t m;
    if (!decode(&m)) return "";
    snprintf(text, sizeof(text), "%d ch, %d Hz, %d samples", m.num_channels, m.sample_rate_hz,
             m.num_samples);
  } else {
    return "";
  }
  return text;
}

std::string JsonEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log info", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log info",
        "Reports what an LCM log holds: per channel the message type, count, rate,\n"
        "size, sequence gaps, time span and sensor geometry (scans, images, grids,\n"
        "audio); and where a truncated or corrupt log breaks (the readable part is\n"
        "still reported).");
    std::string path;
    bool json = false;
    parser.AddPositional("LOG", &path, "LCM log file (as written by lcm-logger / sarmap-log record)");
    parser.AddSwitch("--json", &json, "print JSON instead of a table");
    if (!parser.Parse(argc, argv)) return 0;

    LcmLogReader reader(path);
    std::map<std::string, ChannelSummary> channels;
    LogEvent event;
    int64_t events = 0, first_us = 0, last_us = 0;
    int64_t next_report = 64 << 20;
    while (reader.Next(&event)) {
      if (events == 0) first_us = event.timestamp_us;
      last_us = std::max(last_us, event.timestamp_us);
      ++events;
      ChannelSummary& c = channels[event.channel];
      const std::string type = sarmap::logtools::SarmapTypeName(event.data);
      ++c.types[type.empty() ? "?" : type];
      if (c.count == 0) c.first_us = event.timestamp_us;
      c.last_us = event.timestamp_us;
      ++c.count;
      c.bytes += static_cast<int64_t>(event.data.size());
      int64_t utime, seq;
      if (sarmap::logtools::ReadSarmapHeader(event.data, &utime, &seq)) {
        if (!c.has_header) c.first_utime = utime;
        c.has_header = true;
        c.last_utime = utime;
        c.sequence.Observe(Publisher(type, event.data), seq);
      }
      const std::string geometry = Geometry(type, event.data);
      if (!geometry.empty()) {
        c.geometry_varies = c.geometry_varies || (!c.geometry.empty() && geometry != c.geometry);
        c.geometry = geometry;
      }
      if (!json && reader.offset() > next_report) {
        fprintf(stderr, "\r  read %.0f%% ...", 100.0 * reader.offset() / std::max<int64_t>(1, reader.file_size()));
        next_report += 64 << 20;
      }
    }
    if (!json && next_report > (64 << 20)) fprintf(stderr, "\r                 \r");
    const double span_s = events > 1 ? (last_us - first_us) * 1e-6 : 0.0;

    std::ostringstream out;
    if (json) {
      out << "{\"file\": \"" << JsonEscape(path) << "\", \"bytes\": " << reader.file_size()
          << ", \"events\": " << events << ", \"span_s\": " << span_s << ", \"channels\": [";
      bool first = true;
      for (const auto& [name, c] : channels) {
        const double cspan = (c.last_us - c.first_us) * 1e-6;
        out << (first ? "" : ", ") << "{\"channel\": \"" << JsonEscape(name) << "\", \"type\": \""
            << c.types.rbegin()->first << "\", \"count\": " << c.count << ", \"bytes\": " << c.bytes
            << ", \"rate_hz\": " << (cspan > 0 ? (c.count - 1) / cspan : 0.0)
            << ", \"seq_gaps\": " << c.sequence.gaps()
            << ", \"reordered\": " << c.sequence.reordered() << ", \"geometry\": \""
            << JsonEscape(c.geometry)
            << "\", \"geometry_varies\": " << (c.geometry_varies ? "true" : "false") << "}";
        first = false;
      }
      out << "], \"problems\": [";
      first = true;
      for (const auto& p : reader.problems()) {
        out << (first ? "" : ", ") << "{\"offset\": " << p.file_offset << ", \"after_event\": "
            << p.after_event << ", \"what\": \"" << JsonEscape(p.what) << "\", \"resync_offset\": "
            << p.resync_offset << "}";
        first = false;
      }
      out << "]}\n";
      fputs(out.str().c_str(), stdout);
      return reader.problems().empty() ? 0 : 3;
    }

    char line[512];
    snprintf(line, sizeof(line), "log     %s (%.1f MB)\nevents  %lld over %.2f s\n", path.c_str(),
             reader.file_size() / 1e6, static_cast<long long>(events), span_s);
    out << line;
    if (events > 0) {
      snprintf(line, sizeof(line), "%-22s %-22s %8s %9s %10s %7s %7s %10s  %s\n", "channel", "type",
               "count", "rate_Hz", "kB", "gaps", "reord", "utime_s", "geometry (last message)");
      out << "\n" << line;
      for (const auto& [name, c] : channels) {
        const double cspan = (c.last_us - c.first_us) * 1e-6;
        std::string type;
        for (const auto& [t, n] : c.types) type += (type.empty() ? "" : "+") + t;
        snprintf(line, sizeof(line), "%-22s %-22s %8lld %9.2f %10.1f %7lld %7lld %10.2f%s%s%s\n",
                 name.c_str(), type.c_str(), static_cast<long long>(c.count),
                 cspan > 0 ? (c.count - 1) / cspan : 0.0, c.bytes / 1e3,
                 static_cast<long long>(c.sequence.gaps()),
                 static_cast<long long>(c.sequence.reordered()),
                 c.has_header ? (c.last_utime - c.first_utime) * 1e-6 : 0.0,
                 c.geometry.empty() ? "" : "  ", c.geometry.c_str(),
                 c.geometry_varies ? " (varies)" : "");
        out << line;
      }
    }
    if (!reader.problems().empty()) {
      out << "\nthe log is damaged:\n";
      for (const auto& p : reader.problems()) {
        out << "  breaks at byte " << p.file_offset << " (after event " << p.after_event << "): " << p.what;
        if (p.resync_offset >= 0) {
          out << "; resumed at byte " << p.resync_offset << " (" << (p.resync_offset - p.file_offset)
              << " bytes skipped)\n";
        } else {
          out << "; nothing readable after it\n";
        }
      }
    }
    fputs(out.str().c_str(), stdout);
    return reader.problems().empty() ? 0 : 3;
  });
}
