// The stack under a hostile publisher: the long-running nodes (simulator, depth, SLAM, sound
// localisation, speech, vision, sound map, people map, explorer, monitor, viewer, a procman
// deputy) run as processes over real LCM while sarmap-net-fuzz sends crafted datagrams to
// every channel. Afterwards every node must still be alive and still publishing its
// NODE_STATUS and its outputs, and must have counted hostile datagrams as dropped (so the
// flood reached it). Prints each node's RSS and CPU before and during the flood, and each
// node's own summary (its NODE_STATUS message) after it.
//
// Run by CTest inside tests/harness/sarmap-netns. After the gtest flags, --flood-seconds S
// (default 10), --flood-rate N (datagrams/s, default 2000) and --flood-kinds RE
// (sarmap-net-fuzz --kinds, default all) set the flood; make fuzz runs it longer.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/decode.h"
#include "common/node.h"
#include "common/testing/isolated_network.h"
#include "sarmap/node_status_t.hpp"
#include "tests/process.h"

namespace sarmap {
namespace testing {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// CPU seconds (user + system) and resident memory of a process, from /proc.
struct ProcSample {
  bool ok = false;
  double cpu_s = 0;
  double rss_mb = 0;
  double at_s = 0;
};

ProcSample SampleProc(pid_t pid) {
  ProcSample s;
  s.at_s = Now();
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return s;
  // Fields after the command name (which may hold spaces) in parentheses.
  const size_t close = line.rfind(')');
  if (close == std::string::npos) return s;
  std::istringstream rest(line.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::stod(field);
    if (i == 15) stime = std::stod(field);
  }
  s.cpu_s = (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) s.rss_mb = std::stod(line.substr(6)) / 1024.0;
  }
  s.ok = true;
  return s;
}

double CpuPercent(const ProcSample& a, const ProcSample& b) {
  return b.at_s > a.at_s ? 100.0 * (b.cpu_s - a.cpu_s) / (b.at_s - a.at_s) : 0.0;
}

struct Watched {
  std::string name;  // node_name in its NODE_STATUS
  std::vector<std::string> args;
  std::unique_ptr<Process> process;
  std::string log;
  int64_t statuses = 0;
  double last_status_s = -1;
  int64_t dropped = 0, received = 0, channels = 0;  // from the latest status
  std::string status_message;                       // from the latest status
  ProcSample before_flood, flood_start, flood_end;
  int64_t dropped_before_flood = 0;
};

// The flood, from the command line (main below).
struct Flood {
  std::string seconds = "10";
  std::string rate = "2000";
  std::string kinds = ".*";
};
Flood g_flood;

class NetFuzzTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!sarmap::IsolatedNetwork()) {
      GTEST_FAIL() << "run through tests/harness/sarmap-netns (ctest does): the network fuzzer "
                      "must not reach a real network";
    }
    ASSERT_EQ(chdir(SARMAP_SOURCE_DIR), 0) << SARMAP_SOURCE_DIR;  // nodes read config/ here
    dir_ = ::testing::TempDir() + "/net-fuzz-" + std::to_string(getpid());
    std::string ignored;
    RunCapture({"mkdir", "-p", dir_}, &ignored);
    // The deputy's order key: any 32 bytes, readable by its owner only.
    RunCapture({"sh", "-c", "umask 077 && head -c 32 /dev/urandom > " + dir_ + "/procman.key"},
               &ignored);
  }
  void TearDown() override {
    for (auto& w : nodes_) {
      if (w.process) w.process->Signal(SIGKILL);
    }
    // Kept after a failure: the nodes' output and every datagram sent (sent.lcmlog).
    std::string ignored;
    if (!HasFailure()) {
      RunCapture({"rm", "-rf", dir_}, &ignored);
    } else {
      std::printf("kept %s: each node's output, and every datagram sent in sent.lcmlog\n",
                  dir_.c_str());
    }
  }

 public:
  // The latest NODE_STATUS of each node, matched by name and pid (a forged status from the
  // fuzzer carries neither).
  void OnStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    sarmap::node_status_t s;
    if (!common::DecodeMessage(rbuf->data, rbuf->data_size, &s)) return;
    for (auto& w : nodes_) {
      if (!w.process || s.pid != w.process->pid() || s.node_name != w.name) continue;
      ++w.statuses;
      w.last_status_s = Now();
      w.dropped = w.received = 0;
      for (const auto& c : s.channels) {
        w.dropped += c.dropped_malformed;
        w.received += c.received;
      }
      w.channels = s.num_channels;
      w.status_message = s.message;
    }
  }
  void OnOutput(const lcm::ReceiveBuffer*, const std::string& channel) { ++outputs_[channel]; }

 protected:
  template <class Pred>
  bool SpinUntil(lcm::LCM* lcm, Pred done, double timeout_s) {
    const double deadline = Now() + timeout_s;
    while (!done()) {
      if (Now() > deadline) return false;
      lcm->handleTimeout(20);
    }
    return true;
  }
  void SpinFor(lcm::LCM* lcm, double seconds) {
    const double end = Now() + seconds;
    SpinUntil(
        lcm, [&] { return Now() >= end; }, seconds + 1);
  }

  std::string dir_;
  std::vector<Watched> nodes_;
  std::map<std::string, int64_t> outputs_;
};

std::string Tail(const std::string& text, size_t lines) {
  size_t pos = text.size();
  for (size_t n = 0; n <= lines && pos > 0; ++n) pos = text.rfind('\n', pos - 1);
  return pos == std::string::npos ? text : text.substr(pos + 1);
}

TEST_F(NetFuzzTest, EveryNodeSurvivesAHostilePublisherOnEveryChannel) {
  const std::string flood_s = g_flood.seconds;
  const std::string rate = g_flood.rate;
  const std::string kinds = g_flood.kinds;

  const std::string key = dir_ + "/procman.key";
  const auto add = [&](std::string name, std::vector<std::string> args) {
    Watched w;
    w.name = std::move(name);
    w.args = std::move(args);
    nodes_.push_back(std::move(w));
  };
  add("sarmap-slam", {"sarmap-slam", "--config", "config/slam_kinect_robot.yaml"});
  add("sarmap-sound-map", {"sarmap-sound-map"});
  add("sarmap-people-map", {"sarmap-people-map"});
  add("sarmap-depth", {"sarmap-depth", "--set", "source=lcm"});
  add("sarmap-sound-localisation", {"sarmap-sound-localisation"});
  add("sarmap-speech", {"sarmap-speech"});
  add("sarmap-vision-people", {"sarmap-vision-people"});
  add("sarmap-explore", {"sarmap-explore"});
  add("sarmap-monitor", {"sarmap-monitor", "--set", "print_period_s=0"});
  add("sarmap-viewer", {"sarmap-viewer"});
  add("sarmap-procman-deputy[fuzz]", {"sarmap-procman-deputy", "--id", "fuzz", "--key", key});
  // The simulator last, as the demo starts it: its sensors feed the nodes above.
  add("sarmap-sim",
      {"sarmap-sim", "--world", "config/worlds/lab_dark.yaml", "--duration", "3600", "--speed", "1",
       "--set", "audio.mic_array=respeaker4", "--set", "drive=cmd_vel"});

  lcm::LCM lcm(common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  lcm.subscribe("^NODE_STATUS$", &NetFuzzTest::OnStatus, static_cast<NetFuzzTest*>(this));
  // What each long-running node publishes from the simulator's sensors (or on a timer): every
  // one must be published again once the flood is over (far-future stamps and forged clocks
  // among the datagrams are dropped by each node's stamp gate, never adopted). Speech, the
  // monitor and the viewer publish only NODE_STATUS steadily (speech's PEOPLE_AUDIO needs a
  // call heard), which is checked for every node.
  struct Output {
    const char* channel;
    const char* producer;
  };
  const Output outputs[] = {{"DEPTH", "sarmap-sim"},
                            {"SCAN", "sarmap-depth"},
                            {"DOA", "sarmap-sound-localisation"},
                            {"DOA_MAP", "sarmap-sound-localisation"},
                            {"CMD_VEL", "sarmap-explore"},
                            {"EXPLORE_STATUS", "sarmap-explore"},
                            {"PEOPLE_MAP", "sarmap-people-map"},
                            {"POSE", "sarmap-slam"},
                            {"MAP", "sarmap-slam"},
                            {"SOUND_MAP", "sarmap-sound-map"},
                            {"PEOPLE_VISUAL", "sarmap-vision-people"},
                            {"PM_INFO", "sarmap-procman-deputy[fuzz]"}};
  for (const Output& o : outputs) {
    lcm.subscribe(std::string("^") + o.channel + "$", &NetFuzzTest::OnOutput,
                  static_cast<NetFuzzTest*>(this));
  }
  for (auto& w : nodes_) {
    if (w.name == "sarmap-sim") SpinFor(&lcm, 2.0);  // every node subscribed first
    std::string file = w.args[0];
    w.log = dir_ + "/" + file.substr(file.rfind('/') + 1) + ".txt";
    w.process = std::make_unique<Process>(w.args, w.log);
  }
  const auto all_reporting = [&](double since_s) {
    for (const auto& w : nodes_) {
      if (w.last_status_s < since_s) return false;
    }
    return true;
  };
  const auto report_missing = [&](double since_s) {
    std::string out;
    for (auto& w : nodes_) {
      if (w.last_status_s >= since_s) continue;
      out += "\n" + w.name + (w.process->Running() ? " (running)" : " (exited)") +
             " sent no NODE_STATUS; its output ends with:\n" + Tail(w.process->Output(), 15);
    }
    return out;
  };
  ASSERT_TRUE(SpinUntil(
      &lcm, [&] { return all_reporting(0); }, 30))
      << report_missing(0);

  // A quiet window, then the flood.
  constexpr double kWindowS = 4.0;
  for (auto& w : nodes_) w.before_flood = SampleProc(w.process->pid());
  outputs_.clear();
  SpinFor(&lcm, kWindowS);
  const std::map<std::string, int64_t> outputs_quiet = outputs_;
  for (auto& w : nodes_) {
    w.flood_start = SampleProc(w.process->pid());
    w.dropped_before_flood = w.dropped;
  }
  outputs_.clear();
  Process fuzz({"sarmap-net-fuzz", "--seconds", flood_s, "--rate", rate, "--kinds", kinds,
                "--record", dir_ + "/sent.lcmlog"},
               dir_ + "/net-fuzz.txt");
  const double flood_timeout_s = std::stod(flood_s) + 30;
  ASSERT_TRUE(SpinUntil(
      &lcm, [&] { return !fuzz.Running(); }, flood_timeout_s))
      << fuzz.Output();
  ASSERT_EQ(fuzz.Wait(1), 0) << fuzz.Output();
  for (auto& w : nodes_) w.flood_end = SampleProc(w.process->pid());
  const std::map<std::string, int64_t> outputs_during = outputs_;
  std::printf("%s", fuzz.Output().c_str());

  // After the flood: every node alive and reporting again (its 1 Hz status, timer-driven).
  const double flood_over_s = Now();
  outputs_.clear();
  const bool reporting = SpinUntil(
      &lcm, [&] { return all_reporting(flood_over_s); }, 15);
  outputs_.clear();
  SpinFor(&lcm, kWindowS);  // what the pipeline still publishes
  const std::map<std::string, int64_t> outputs_after = outputs_;
  // An output with a long period (MAP: 5 s of scan time) may fall outside the window: waited
  // for a while longer.
  const auto all_outputs_seen = [&] {
    for (const Output& o : outputs) {
      if (!outputs_.count(o.channel)) return false;
    }
    return true;
  };
  SpinUntil(&lcm, all_outputs_seen, 15);
  const std::map<std::string, int64_t> outputs_later = outputs_;

  std::printf("\n%-28s %9s %9s %9s %9s %10s %9s\n", "node", "RSS MB", "RSS MB", "CPU %", "CPU %",
              "dropped", "statuses");
  std::printf("%-28s %9s %9s %9s %9s %10s %9s\n", "", "before", "flood end", "quiet", "flood",
              "in flood", "");
  for (const auto& w : nodes_) {
    std::printf("%-28s %9.1f %9.1f %9.1f %9.1f %10lld %9lld\n", w.name.c_str(),
                w.before_flood.rss_mb, w.flood_end.rss_mb,
                CpuPercent(w.before_flood, w.flood_start), CpuPercent(w.flood_start, w.flood_end),
                static_cast<long long>(w.dropped - w.dropped_before_flood),
                static_cast<long long>(w.statuses));
  }
  std::printf("\neach node's own summary after the flood (NODE_STATUS message):\n");
  for (const auto& w : nodes_) {
    std::printf("  %-28s %s\n", w.name.c_str(), w.status_message.c_str());
  }
  const auto count = [](const std::map<std::string, int64_t>& m, const char* channel) {
    const auto it = m.find(channel);
    return static_cast<long long>(it == m.end() ? 0 : it->second);
  };
  std::printf(
      "\nmessages on the output channels in %.0f s before the flood, during it (the "
      "fuzzer's included), in %.0f s after it (up to 15 s more for the first one):\n",
      kWindowS, kWindowS);
  for (const Output& o : outputs) {
    std::printf("  %-15s %-28s %6lld %6lld %6lld%s\n", o.channel, o.producer,
                count(outputs_quiet, o.channel), count(outputs_during, o.channel),
                count(outputs_after, o.channel),
                count(outputs_later, o.channel) == 0   ? "   stopped after the flood"
                : count(outputs_after, o.channel) == 0 ? "   (later)"
                                                       : "");
  }
  std::fflush(stdout);

  for (auto& w : nodes_) {
    EXPECT_TRUE(w.process->Running())
        << w.name << " died in the flood (exit " << w.process->Wait(0) << "); the datagrams sent "
        << "are in " << dir_ << "/sent.lcmlog; its output ends with:\n"
        << Tail(w.process->Output(), 20);
  }
  EXPECT_TRUE(reporting) << "silent after the flood:" << report_missing(flood_over_s);
  for (const auto& w : nodes_) {
    // Every node that subscribes to something counted hostile datagrams: the flood reached it.
    if (w.channels > 0) {
      EXPECT_GT(w.dropped, w.dropped_before_flood) << w.name << " dropped nothing";
    }
  }

  for (const Output& o : outputs) {
    EXPECT_GT(count(outputs_later, o.channel), 0)
        << o.channel << " (" << o.producer << ") stopped after the flood";
  }

  // A clean stop on SIGINT.
  for (auto& w : nodes_) w.process->Signal(SIGINT);
  for (auto& w : nodes_) {
    const int code = w.process->Wait(15);
    if (code != 0) {
      std::printf("%s: exit %d after SIGINT%s\n", w.name.c_str(), code,
                  code == -1 ? " (still running after 15 s; killed)" : "");
    }
    EXPECT_TRUE(code == 0 || code == -1 || code == 128 + SIGINT)
        << w.name << " exited with " << code << " on SIGINT; output:\n"
        << Tail(w.process->Output(), 20);
  }
}

// LCM's own UDP protocol with hostile headers (sarmap-net-fuzz --raw-lcm), for the receive
// thread of liblcm inside every process. Without the filter of common/lcm_guard.h one
// fragment whose offset + length wraps past 2^32 to below its message size ("LC03", message
// 100 bytes, offset 0xfffffff0, fragment 0 of 2, a subscribed channel, 32 bytes: 57 bytes in
// all) passes liblcm 1.3.1's bounds check and is copied 4 GB past its buffer: SIGSEGV.
TEST_F(NetFuzzTest, NodesSurviveHostileLcmFragmentHeaders) {
  nodes_.resize(3);
  nodes_[0].name = "sarmap-monitor";
  nodes_[0].args = {"sarmap-monitor", "--set", "print_period_s=0"};
  nodes_[1].name = "sarmap-people-map";
  nodes_[1].args = {"sarmap-people-map"};
  nodes_[2].name = "sarmap-procman-deputy[fuzz]";
  nodes_[2].args = {"sarmap-procman-deputy", "--id", "fuzz", "--key", dir_ + "/procman.key"};
  lcm::LCM lcm(common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  lcm.subscribe("^NODE_STATUS$", &NetFuzzTest::OnStatus, static_cast<NetFuzzTest*>(this));
  for (auto& w : nodes_) {
    w.process = std::make_unique<Process>(w.args, dir_ + "/" + w.args[0] + ".txt");
  }
  const auto all_since = [&](double since_s) {
    for (const auto& w : nodes_) {
      if (w.last_status_s <= since_s) return false;
    }
    return true;
  };
  ASSERT_TRUE(SpinUntil(
      &lcm, [&] { return all_since(0); }, 20));
  Process fuzz({"sarmap-net-fuzz", "--raw-lcm", "--seconds", "2", "--rate", "200", "--channels",
                "^(POSE|PEOPLE_VISUAL|SOUND_MAP|ODOM|SCAN|PM_ORDERS)$"},
               dir_ + "/net-fuzz.txt");
  ASSERT_TRUE(SpinUntil(
      &lcm, [&] { return !fuzz.Running(); }, 30));
  const double flood_over_s = Now();
  SpinUntil(
      &lcm, [&] { return all_since(flood_over_s); }, 10);
  std::printf("%s", fuzz.Output().c_str());
  for (auto& w : nodes_) {
    EXPECT_TRUE(w.process->Running()) << w.name << " died (exit " << w.process->Wait(0) << ")";
    EXPECT_GT(w.last_status_s, flood_over_s) << w.name << " silent after the raw datagrams";
  }
}

}  // namespace
}  // namespace testing
}  // namespace sarmap

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);  // removes the gtest flags
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 < argc && flag == "--flood-seconds") {
      sarmap::testing::g_flood.seconds = argv[++i];
    } else if (i + 1 < argc && flag == "--flood-rate") {
      sarmap::testing::g_flood.rate = argv[++i];
    } else if (i + 1 < argc && flag == "--flood-kinds") {
      sarmap::testing::g_flood.kinds = argv[++i];
    } else {
      std::fprintf(stderr,
                   "usage: net_fuzz_test [gtest flags] [--flood-seconds S] [--flood-rate N] "
                   "[--flood-kinds RE]\n");
      return 2;
    }
  }
  return RUN_ALL_TESTS();
}
