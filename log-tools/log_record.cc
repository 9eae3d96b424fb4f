// sarmap-log record: writes every LCM message whose channel matches a regular expression to an
// LCM log (the event log format of lcm-logger, read by lcm-logplayer and every sarmap log
// reader), until SIGINT or SIGTERM.
//
// Its own recorder rather than Debian's lcm-logger: liblcm 1.3.1's receive thread can be crashed
// by one hostile fragment header (components/common/lcm_guard.h), and a recorder subscribed to
// every channel is exposed to all of them. This one attaches the kernel filter of lcm_guard.h
// to its receive socket before it handles the first message.
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/lcm_guard.h"
#include "common/node.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "common/signal_handlers.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/record_profile.h"

namespace {

// LCM_MAX_MESSAGE_SIZE of liblcm 1.3.1 (not in its public headers).
constexpr uint32_t kMaxLcmMessageBytes = 1u << 28;

volatile sig_atomic_t g_stop = 0;
void OnStop(int) { g_stop = 1; }

bool Exists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

// Microseconds since the epoch, the clock of liblcm's receive times.
int64_t WallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double SteadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// liblcm drops datagrams when its socket buffer fills; a recorder of every channel (RGB-D
// frames included) wants a large one even when the URL given does not ask for it.
std::string WithReceiveBuffer(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=8388608";
}

class Recorder {
 public:
  Recorder(std::string base, bool increment, bool force, int64_t split_bytes,
           std::unique_ptr<sarmap::logtools::RecordThinner> thinner)
      : base_(std::move(base)),
        increment_(increment),
        force_(force),
        split_bytes_(split_bytes),
        thinner_(std::move(thinner)) {
    Open();
  }

  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (!error_.empty()) return;
    // An empty message is no message (every LCM type starts with its fingerprint), and the
    // log format's readers stop at an event with no data. A size above what LCM can send is
    // liblcm's reading of a hostile datagram (its size wrapped below zero): counted, not
    // written.
    if (rbuf->data_size == 0 || rbuf->data_size > kMaxLcmMessageBytes || channel.empty()) {
      ++skipped_;
      return;
    }
    if (thinner_) {
      sarmap::logtools::LogEvent event;
      event.timestamp_us = rbuf->recv_utime;
      event.channel = channel;
      const auto* bytes = static_cast<const uint8_t*>(rbuf->data);
      event.data.assign(bytes, bytes + rbuf->data_size);
      thinner_->Add(std::move(event));
      Release(rbuf->recv_utime);
      return;
    }
    Write(rbuf->recv_utime, channel, rbuf->data, rbuf->data_size);
  }

  // With a profile: writes what the thinner has decided by `now_utime` (wall clock, us).
  void Release(int64_t now_utime) {
    if (!thinner_ || !error_.empty()) return;
    released_.clear();
    thinner_->Release(now_utime, &released_);
    WriteReleased();
  }

  void Write(int64_t timestamp_us, const std::string& channel, const void* data, uint32_t size) {
    // Event header: sync word, event number, timestamp, channel length, data length.
    const int64_t bytes = 28 + static_cast<int64_t>(channel.size()) + size;
    if (split_bytes_ > 0 && file_bytes_ > 0 && file_bytes_ + bytes > split_bytes_) {
      Close();
      try {  // not through liblcm's C dispatch: the main loop reports it
        Open();
      } catch (const std::exception& e) {
        error_ = e.what();
        return;
      }
    }
    try {  // not through liblcm's C dispatch: the main loop reports it
      log_->WriteBytes(channel, data, size, timestamp_us);
    } catch (const std::exception& e) {
      error_ =
          std::string(e.what()) + " (channel " + channel + ", " + std::to_string(size) + " bytes)";
      return;
    }
    ++events_;
    file_bytes_ += bytes;
    total_bytes_ += bytes;
  }

  // Pushes what is buffered to the file (a killed recorder loses at most one interval).
  void Flush() {
    if (!log_ || !error_.empty()) return;
    try {
      log_->Flush();
    } catch (const std::exception& e) {
      error_ = e.what();
    }
  }
  // End of the recording: with a profile, what is still held is decided and written.
  void Finish() {
    if (!thinner_ || !log_ || !error_.empty()) return;
    released_.clear();
    thinner_->Finish(&released_);
    WriteReleased();
  }
  void Close() {
    Flush();
    log_.reset();
  }

  const std::string& path() const { return path_; }
  const std::string& error() const { return error_; }
  int64_t events() const { return events_; }
  int64_t skipped() const { return skipped_; }  // empty or impossible sizes
  int64_t total_bytes() const { return total_bytes_; }
  const sarmap::logtools::RecordThinner* thinner() const { return thinner_.get(); }

 private:
  void WriteReleased() {
    for (const auto& e : released_) {
      if (!error_.empty()) return;
      Write(e.timestamp_us, e.channel, e.data.data(), static_cast<uint32_t>(e.data.size()));
    }
  }

  // The next file: BASE, or with increment (and every split) BASE.NN, the first NN (from 00)
  // that does not exist yet, as lcm-logger names them.
  void Open() {
    if (increment_ || split_bytes_ > 0) {
      for (int n = next_suffix_;; ++n) {
        char suffix[16];
        std::snprintf(suffix, sizeof(suffix), ".%02d", n);
        if (!Exists(base_ + suffix)) {
          path_ = base_ + suffix;
          next_suffix_ = n + 1;
          break;
        }
      }
    } else {
      path_ = base_;
      if (Exists(path_) && !force_) {
        throw sarmap::common::ArgError(path_ + " exists (--force to overwrite, --increment for " +
                                       "a new numbered file)");
      }
    }
    log_ = std::make_unique<sarmap::logtools::LcmLogWriter>(path_);
    file_bytes_ = 0;
  }

  std::string base_;
  bool increment_, force_;
  int64_t split_bytes_;
  int next_suffix_ = 0;
  std::unique_ptr<sarmap::logtools::RecordThinner> thinner_;
  std::vector<sarmap::logtools::LogEvent> released_;
  std::unique_ptr<sarmap::logtools::LcmLogWriter> log_;
  std::string path_, error_;
  int64_t events_ = 0, skipped_ = 0, file_bytes_ = 0, total_bytes_ = 0;
};

int Record(int argc, char** argv) {
  sarmap::common::ArgParser parser(
      "sarmap-log record",
      "Records sarmap channels to an LCM log (lcm-logger's format) until SIGINT or SIGTERM.");
  std::string output, channels = ".*", url, profile;
  std::vector<std::string> overrides;
  bool force = false, increment = false, quiet = false;
  int flush_interval_ms = 100;
  double split_mb = 0;
  parser.AddFlag("-o", &output, "output log (default: sarmap-YYYYmmdd-HHMMSS.lcmlog)");
  parser.AddFlag("--channels", &channels, "regular expression of channels to record");
  parser.AddFlag("--lcm-url", &url, "LCM URL (default: the sarmap default)");
  parser.AddSwitch("--force", &force, "overwrite an existing file");
  parser.AddSwitch("--increment", &increment,
                   "write FILE.00, or FILE.01, ...: the first that does not exist");
  parser.AddFlag("--split-mb", &split_mb,
                 "start the next numbered file (as --increment) once a file reaches this size; 0: "
                 "one file");
  parser.AddFlag("--flush-interval", &flush_interval_ms, "flush the file every this many ms");
  parser.AddFlag("--profile", &profile,
                 "thin the camera frames and grids as this file says (e.g. "
                 "config/record_long.yaml: 1 frame/s, every frame around a person seen)");
  parser.AddRepeated("--set", &overrides,
                     "override a profile option, e.g. --set frames.rate_hz=2 (needs --profile)");
  parser.AddSwitch("-q", &quiet, "no summary line at the end");
  if (!parser.Parse(argc, argv)) return 0;
  if (!overrides.empty() && profile.empty())
    throw sarmap::common::ArgError("--set needs --profile");
  std::unique_ptr<sarmap::logtools::RecordThinner> thinner;
  if (!profile.empty()) {
    thinner = std::make_unique<sarmap::logtools::RecordThinner>(
        sarmap::common::LoadOptions<sarmap::logtools::RecordProfileOptions>(
            sarmap::common::ResolveConfigPath(profile), overrides));
  }
  if (flush_interval_ms < 1) throw sarmap::common::ArgError("--flush-interval must be >= 1 ms");
  if (!(split_mb >= 0)) throw sarmap::common::ArgError("--split-mb must be >= 0");
  if (force && (increment || split_mb > 0)) {
    throw sarmap::common::ArgError("--force: not with --increment or --split-mb");
  }
  if (output.empty()) {
    char name[64];
    const time_t now = time(nullptr);
    strftime(name, sizeof(name), "sarmap-%Y%m%d-%H%M%S.lcmlog", localtime(&now));
    output = name;
  }
  if (url.empty()) url = sarmap::common::DefaultLcmUrl();
  url = WithReceiveBuffer(url);

  sarmap::common::SetSignalHandler({SIGINT, SIGTERM}, OnStop);

  Recorder recorder(output, increment, force, static_cast<int64_t>(split_mb * 1024 * 1024),
                    std::move(thinner));
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    throw std::runtime_error("cannot initialise LCM on '" + url +
                             "' (is there a multicast route? see README, 'Networking')");
  }
  lcm.subscribe(channels, &Recorder::OnMessage, &recorder);
  // Without the filter it still records (as lcm-logger would), saying so.
  std::string guard_error;
  const int guarded = sarmap::common::GuardLcmReceiveSocket(&lcm, url, &guard_error);
  if (guarded < 0) {
    fprintf(stderr, "sarmap-log record: warning: no filter for hostile LCM fragments: %s\n",
            guard_error.c_str());
  } else if (guarded == 0 && url.rfind("udpm://", 0) == 0) {
    fprintf(stderr, "sarmap-log record: warning: no LCM receive socket found to filter\n");
  }
  fprintf(stderr, "sarmap-log record: writing %s (Ctrl-C to stop)\n", recorder.path().c_str());

  const double flush_period_s = flush_interval_ms / 1000.0;
  double next_flush_s = SteadyNowS() + flush_period_s;
  while (!g_stop && recorder.error().empty()) {
    // A signal interrupts the wait (-1 with g_stop set): the loop ends.
    if (lcm.handleTimeout(std::min(flush_interval_ms, 100)) < 0 && !g_stop && errno != EINTR) {
      throw std::runtime_error(std::string("LCM receive failed: ") + std::strerror(errno));
    }
    recorder.Release(WallUtime());
    if (SteadyNowS() >= next_flush_s) {
      recorder.Flush();
      next_flush_s = SteadyNowS() + flush_period_s;
    }
  }
  recorder.Finish();
  recorder.Close();
  if (!recorder.error().empty()) throw std::runtime_error(recorder.error());
  if (!quiet) {
    fprintf(stderr,
            "sarmap-log record: %lld events, %.1f MB, %lld empty or impossible messages skipped, "
            "last file %s\n",
            static_cast<long long>(recorder.events()), recorder.total_bytes() / 1e6,
            static_cast<long long>(recorder.skipped()), recorder.path().c_str());
    if (recorder.thinner()) {
      fprintf(stderr, "%s", sarmap::logtools::ThinSummary(*recorder.thinner()).c_str());
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log record", [&] { return Record(argc, argv); });
}
