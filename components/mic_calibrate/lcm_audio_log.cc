#include "mic_calibrate/lcm_audio_log.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "common/decode.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/lcm_log_writer.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/sim_truth_t.hpp"

namespace sarmap {
namespace mic_calibrate {

namespace {
struct Block {
  int64_t first = 0, utime = 0;
  std::vector<int16_t> samples;  // interleaved
};
struct Device {
  std::string channel;
  int rate = 0, num_channels = 0;
  std::vector<Block> blocks;
};
}  // namespace

Recording ReadLcmAudioLog(const std::string& path, const std::string& prefix,
                          LcmAudioLogStats* stats) {
  logtools::LcmLogReader log(path);  // read past damage; where it breaks is a warning
  LcmAudioLogStats st;
  std::map<std::string, Device> devices;
  std::map<std::string, int> bad_by_channel;
  logtools::LogEvent event;
  while (log.Next(&event)) {
    const logtools::LogEvent* ev = &event;
    if (ev->channel.rfind(prefix, 0) != 0) continue;
    sarmap::audio_frame_t msg;
    if (!common::DecodeMessage(ev->data.data(), ev->data.size(), &msg)) {
      ++bad_by_channel[ev->channel];
      continue;
    }
    const bool ok = msg.num_channels > 0 && msg.num_samples >= 0 && msg.sample_rate_hz > 0 &&
                    msg.num_values == int64_t(msg.num_channels) * msg.num_samples &&
                    static_cast<int>(msg.samples.size()) == msg.num_values &&
                    msg.first_sample_index >= 0 &&
                    msg.sample_format == sarmap::audio_frame_t::SAMPLE_INT16;
    Device& d = devices[ev->channel];
    if (!ok || (d.rate && (d.rate != msg.sample_rate_hz || d.num_channels != msg.num_channels))) {
      ++bad_by_channel[ev->channel];
      continue;
    }
    d.channel = ev->channel;
    d.rate = msg.sample_rate_hz;
    d.num_channels = msg.num_channels;
    d.blocks.push_back({msg.first_sample_index, msg.header.utime, std::move(msg.samples)});
    ++st.frames;
  }
  for (const auto& p : log.problems()) st.warnings.push_back(logtools::DescribeProblem(p));
  for (auto& [ch, n] : bad_by_channel) {
    st.bad_frames += n;
    st.warnings.push_back(ch + ": " + std::to_string(n) + " malformed audio frames skipped");
  }
  for (auto it = devices.begin(); it != devices.end();) {
    if (it->second.blocks.empty()) it = devices.erase(it); else ++it;
  }
  if (devices.empty()) {
    throw std::runtime_error(path + ": no valid audio_frame_t on channels starting with '" + prefix + "'");
  }
  st.devices = static_cast<int>(devices.size());
  const int rate = devices.begin()->second.rate;
  for (auto& [ch, d] : devices) {
    if (d.rate != rate) {
      throw std::runtime_error("device " + ch + " runs at " + std::to_string(d.rate) +
                               " Hz, the reference at " + std::to_string(rate) +
                               " Hz: resample to one nominal rate first");
    }
  }
  Recording rec;
  rec.sample_rate_hz = rate;
  // Reference time line: the first sample of the first device.
  double t_ref = 0;
  bool have_ref = false;
  for (auto& [ch, d] : devices) {
    std::sort(d.blocks.begin(), d.blocks.end(),
              [](const Block& a, const Block& b) { return a.first < b.first; });
    const int64_t first = d.blocks.front().first;
    int64_t end = first;
    for (const auto& b : d.blocks)
      end = std::max<int64_t>(end, b.first + static_cast<int64_t>(b.samples.size()) / d.num_channels);
    const size_t len = static_cast<size_t>(end - first);
    // utime of sample `first`: the median over blocks of utime - (index - first) / rate, which
    // is robust to a late block.
    std::vector<double> starts;
    for (const auto& b : d.blocks) starts.push_back(b.utime * 1e-6 - double(b.first - first) / rate);
    std::nth_element(starts.begin(), starts.begin() + starts.size() / 2, starts.end());
    const double t0 = starts[starts.size() / 2];
    if (!have_ref) {
      t_ref = t0;
      have_ref = true;
      rec.reference_start_utime = std::llround(t0 * 1e6);
    }
    int64_t gaps = 0, covered = 0;
    std::vector<std::vector<float>> chans(d.num_channels, std::vector<float>(len, 0.0f));
    for (const auto& b : d.blocks) {
      const int64_t n = static_cast<int64_t>(b.samples.size()) / d.num_channels;
      for (int64_t i = 0; i < n; ++i)
        for (int c = 0; c < d.num_channels; ++c)
          chans[c][b.first - first + i] = b.samples[i * d.num_channels + c] / 32768.0f;
      covered += n;
    }
    gaps = static_cast<int64_t>(len) - covered;
    if (gaps > 0) {
      st.warnings.push_back(ch + ": " + std::to_string(gaps) +
                            " samples missing from the sample counter (silence inserted)");
    }
    for (int c = 0; c < d.num_channels; ++c) {
      rec.channels.push_back(std::move(chans[c]));
      rec.channel_start_s.push_back(t0 - t_ref);
      rec.channel_names.push_back(ch + ":" + std::to_string(c));
    }
  }
  if (stats) *stats = st;
  return rec;
}

std::vector<common::StampedPose> ReadLcmPoses(const std::string& path, const std::string& channel,
                                              LcmAudioLogStats* stats) {
  logtools::LcmLogReader log(path);
  std::vector<common::StampedPose> poses;
  int bad = 0;
  auto make = [](int64_t utime, const double* p, const double* q) {
    common::StampedPose sp;
    sp.utime = utime;
    sp.pose = common::Rigid3d(Eigen::Vector3d(p[0], p[1], p[2]),
                              Eigen::Quaterniond(q[0], q[1], q[2], q[3]));
    return sp;
  };
  logtools::LogEvent event;
  while (log.Next(&event)) {
    const logtools::LogEvent* ev = &event;
    if (ev->channel != channel) continue;
    sarmap::odometry_t odom;
    sarmap::pose_t pose;
    sarmap::sim_truth_t truth;
    const double* q = nullptr;
    const size_t size = ev->data.size();
    if (common::DecodeMessage(ev->data.data(), size, &odom)) {
      poses.push_back(make(odom.header.utime, odom.position_m, odom.orientation));
      q = odom.orientation;
    } else if (common::DecodeMessage(ev->data.data(), size, &pose)) {
      poses.push_back(make(pose.header.utime, pose.position_m, pose.orientation));
      q = pose.orientation;
    } else if (common::DecodeMessage(ev->data.data(), size, &truth)) {
      poses.push_back(make(truth.header.utime, truth.robot_position_m, truth.robot_orientation));
      q = truth.robot_orientation;
    } else {
      ++bad;
      continue;
    }
    const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(std::abs(qn - 1) < 1e-3) || !poses.back().pose.translation().allFinite()) {
      poses.pop_back();
      ++bad;
    }
  }
  if (stats) {
    for (const auto& p : log.problems()) stats->warnings.push_back(logtools::DescribeProblem(p));
  }
  if (stats && bad > 0) {
    stats->warnings.push_back(channel + ": " + std::to_string(bad) +
                              " messages that are not a valid odometry_t / pose_t / sim_truth_t skipped");
  }
  if (poses.empty()) {
    throw std::runtime_error(path + ": no odometry_t, pose_t or sim_truth_t on channel '" + channel + "'");
  }
  std::stable_sort(poses.begin(), poses.end(),
                   [](const common::StampedPose& a, const common::StampedPose& b) { return a.utime < b.utime; });
  return poses;
}

void WriteLcmAudioLog(const std::string& path, const Recording& rec,
                      const std::vector<std::vector<int>>& devices, int64_t start_utime,
                      int block) {
  logtools::LcmLogWriter log(path);
  struct Pending {
    int64_t utime;
    std::string channel;
    std::vector<uint8_t> bytes;
  };
  std::vector<Pending> events;
  for (size_t d = 0; d < devices.size(); ++d) {
    const auto& chans = devices[d];
    const std::string name = "AUDIO_CARD" + std::to_string(d + 1);
    const double start = rec.channel_start_s.empty() ? 0.0 : rec.channel_start_s[chans[0]];
    const size_t len = rec.channels[chans[0]].size();
    int64_t seq = 0;
    for (size_t i0 = 0; i0 < len; i0 += block) {
      const int n = static_cast<int>(std::min<size_t>(block, len - i0));
      sarmap::audio_frame_t msg;
      msg.header.utime = start_utime + std::llround((start + double(i0) / rec.sample_rate_hz) * 1e6);
      msg.header.seq = seq++;
      msg.header.frame = "mic_array";
      msg.device_id = name;
      msg.sample_rate_hz = static_cast<int32_t>(std::lround(rec.sample_rate_hz));
      msg.num_channels = static_cast<int16_t>(chans.size());
      msg.num_samples = n;
      msg.first_sample_index = static_cast<int64_t>(i0);
      msg.overrun_samples = 0;
      msg.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
      msg.num_values = n * msg.num_channels;
      msg.samples.resize(msg.num_values);
      for (int i = 0; i < n; ++i)
        for (size_t c = 0; c < chans.size(); ++c) {
          const float v = std::clamp(rec.channels[chans[c]][i0 + i], -1.0f, 1.0f);
          msg.samples[i * chans.size() + c] = static_cast<int16_t>(std::lround(v * 32767.0f));
        }
      Pending p{msg.header.utime, name, std::vector<uint8_t>(msg.getEncodedSize())};
      msg.encode(p.bytes.data(), 0, static_cast<int>(p.bytes.size()));
      events.push_back(std::move(p));
    }
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Pending& a, const Pending& b) { return a.utime < b.utime; });
  for (const auto& p : events) log.WriteBytes(p.channel, p.bytes, p.utime);
}

}  // namespace mic_calibrate
}  // namespace sarmap
