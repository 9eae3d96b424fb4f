// sarmap-decode-fuzz-driver: runs the decode fuzz target (decode_fuzz_target.cc) without
// libFuzzer, with the project's own compiler, for a bounded number of inputs:
//   1. the seed corpus: random and sane encodings of every message type;
//   2. a structured sweep of every seed: each string length, array count and stamp set to
//      each hostile value, NaN and infinity in each number, hostile contents in each string,
//      every truncation and trailing bytes;
//   3. --iterations random hostile datagrams (tests/fuzz/wire_mutations.h), some mutated
//      twice, some another type's message, some random bytes;
//   4. every FILE given, and every file in each DIR given (a libFuzzer corpus or crash).
// The target aborts on a finding; this driver also fails an input whose decode made one
// allocation larger than 1 MiB + 64 x its size (operator new is replaced in this binary).
//
//   sarmap-decode-fuzz-driver [--iterations N] [--seed S] [FILE|DIR...]
//   sarmap-decode-fuzz-driver --write-corpus DIR    the seed corpus for libFuzzer, then exit
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "common/args.h"
#include "tests/fuzz/wire_mutations.h"
#include "tests/largest_allocation.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {
int64_t g_decoded_messages = 0;
int64_t g_accepted_messages = 0;
}  // namespace

// Each decode is one window of the largest-allocation measure.
extern "C" void SarmapFuzzDecodeBegin() { sarmap::testing::StartMeasuringAllocations(); }

extern "C" void SarmapFuzzDecodeEnd(const char* type, size_t size, bool message, bool accepted) {
  sarmap::testing::StopMeasuringAllocations();
  const size_t limit = (size_t{1} << 20) + 64 * size;
  const size_t largest = sarmap::testing::LargestAllocation();
  if (largest > limit) {
    std::fprintf(stderr, "decode fuzz: %s: one allocation of %zu bytes for an input of %zu bytes\n",
                 type, largest, size);
    std::abort();
  }
  if (message) {
    ++g_decoded_messages;
    g_accepted_messages += accepted;
  }
}

namespace sarmap {
namespace testing {
namespace {

// Fixed so that a run is repeatable: the stamps are hostile relative to this "now".
constexpr int64_t kNowUtime = 1800000000000000;  // 2027-01-15

struct Counts {
  int64_t corpus = 0, structured = 0, random = 0, files = 0;
};

// What runs now, for the crash report: a signal handler may only write what is ready.
char g_label[512] = "";
const Bytes* g_input = nullptr;

void SetLabel(const std::string& text) {
  std::snprintf(g_label, sizeof g_label, "%s", text.c_str());
}

// On a crash (or the target's abort): which input, and the input itself in
// decode-fuzz-crash.bin in the working directory, to replay with this driver or libFuzzer.
void OnCrash(int sig) {
  const char head[] = "decode fuzz: crashed on input: ";
  (void)!write(2, head, sizeof head - 1);
  (void)!write(2, g_label, strlen(g_label));
  const char tail[] = "\ndecode fuzz: the input is in decode-fuzz-crash.bin\n";
  (void)!write(2, tail, sizeof tail - 1);
  const int fd = open("decode-fuzz-crash.bin", O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0 && g_input != nullptr) {
    (void)!write(fd, g_input->data(), g_input->size());
    close(fd);
  }
  signal(sig, SIG_DFL);
  raise(sig);
}

void Run(const Bytes& input, int64_t* counter) {
  g_input = &input;
  LLVMFuzzerTestOneInput(input.data(), input.size());
  g_input = nullptr;
  ++*counter;
}

void Run(const std::string& label, const Bytes& input, int64_t* counter) {
  SetLabel(label);
  Run(input, counter);
}

// Every hostile value of every field of one valid encoding.
void Sweep(const std::string& type, const Bytes& valid, const WireFields& fields,
           int64_t* counter) {
  Bytes wire;
  SetLabel(type + " structured sweep (fields of a valid sample)");
  for (const WireSlot& s : fields.strings) {
    for (int64_t v : HostileStringLengths(valid.size() - s.offset - 4)) {
      wire = valid;
      PutBigEndian(&wire, s.offset, 4, static_cast<uint64_t>(v));
      Run(type + " " + s.path + " length " + std::to_string(v), wire, counter);
    }
    for (const std::string& text : HostileStrings()) {
      Run(type + " " + s.path + " = a hostile string of " + std::to_string(text.size()) + " bytes",
          SpliceString(valid, s, text), counter);
    }
  }
  for (const WireSlot& c : fields.counts) {
    for (int64_t v : HostileCounts(valid.size() - c.offset - c.bytes)) {
      wire = valid;
      PutBigEndian(&wire, c.offset, c.bytes, static_cast<uint64_t>(v));
      Run(type + " " + c.path + " count " + std::to_string(v), wire, counter);
    }
  }
  for (const WireSlot& p : fields.primitives) {
    if (p.bytes == 8 && p.path.size() >= 5 && p.path.compare(p.path.size() - 5, 5, "utime") == 0) {
      for (int64_t v : HostileStamps(kNowUtime)) {
        wire = valid;
        PutBigEndian(&wire, p.offset, 8, static_cast<uint64_t>(v));
        Run(type + " " + p.path + " = " + std::to_string(v), wire, counter);
      }
    }
    // The first element of each number field (and, for arrays, all of them).
    SetLabel(type + " " + p.path + " = NaN, infinity or an extreme number");
    if (p.bytes % 8 == 0) {
      for (uint64_t v : HostileDoubleBits()) {
        wire = valid;
        PutBigEndian(&wire, p.offset, 8, v);
        Run(wire, counter);
        for (size_t i = 8; i < p.bytes; i += 8) PutBigEndian(&wire, p.offset + i, 8, v);
        if (p.bytes > 8) Run(wire, counter);
      }
    }
    if (p.bytes % 4 == 0) {
      for (uint32_t v : HostileFloatBits()) {
        wire = valid;
        PutBigEndian(&wire, p.offset, 4, v);
        Run(wire, counter);
      }
    }
  }
  SetLabel(type + " truncated or with trailing bytes");
  for (size_t size = 0; size < valid.size(); ++size) {
    Run(Bytes(valid.begin(), valid.begin() + static_cast<std::ptrdiff_t>(size)), counter);
  }
  for (size_t extra : {1, 7, 64}) {
    wire = valid;
    wire.resize(valid.size() + extra, 0xa5);
    Run(wire, counter);
  }
}

void RunRandom(int iterations, uint64_t seed, HostileDatagrams* hostile, int64_t* counter) {
  std::mt19937_64 rng(seed);
  std::vector<std::string> types;
  for (const auto& [name, corpus] : hostile->corpora()) types.push_back(name);
  std::string kind, what;
  for (int i = 0; i < iterations; ++i) {
    const std::string& type = types[rng() % types.size()];
    Bytes wire = hostile->Next(type, &kind, &what);
    std::string label = type + " random #" + std::to_string(i) + ": " + kind + ", " + what;
    switch (rng() % 8) {
      case 0: {  // a second mutation on top: flip bytes of the hostile datagram
        for (int k = 0; k < 3 && !wire.empty(); ++k) {
          wire[rng() % wire.size()] ^= static_cast<uint8_t>(1 + rng() % 255);
        }
        label += ", then 3 bytes flipped";
        break;
      }
      case 1: {  // spliced: the head of this one and the tail of another type's
        const Bytes other = hostile->Next(types[rng() % types.size()], &kind, &what);
        const size_t cut = wire.empty() ? 0 : rng() % wire.size();
        const size_t from = other.empty() ? 0 : rng() % other.size();
        wire.resize(cut);
        wire.insert(wire.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
        label += ", spliced at " + std::to_string(cut) + " with another: " + kind + ", " + what;
        break;
      }
      default:
        break;
    }
    Run(label, wire, counter);
  }
}

bool ReadFile(const std::string& path, Bytes* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out->assign(std::istreambuf_iterator<char>(in), {});
  return true;
}

// Files in `path` (a directory, not recursive) or `path` itself.
std::vector<std::string> InputFiles(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw common::ArgError("no such file or directory: " + path);
  if (!S_ISDIR(st.st_mode)) return {path};
  std::vector<std::string> out;
  if (DIR* dir = opendir(path.c_str())) {
    while (const dirent* e = readdir(dir)) {
      const std::string file = path + "/" + e->d_name;
      if (stat(file.c_str(), &st) == 0 && S_ISREG(st.st_mode)) out.push_back(file);
    }
    closedir(dir);
  }
  return out;
}

int WriteCorpus(const std::string& dir, const HostileDatagrams& hostile) {
  mkdir(dir.c_str(), 0755);
  int written = 0;
  for (const auto& [name, corpus] : hostile.corpora()) {
    for (size_t i = 0; i < corpus.valid.size(); ++i) {
      const std::string path = dir + "/" + name + "-" + std::to_string(i);
      std::ofstream out(path, std::ios::binary);
      out.write(reinterpret_cast<const char*>(corpus.valid[i].data()),
                static_cast<std::streamsize>(corpus.valid[i].size()));
      if (!out) throw std::runtime_error("cannot write " + path);
      ++written;
    }
  }
  std::printf("wrote %d seed inputs (%zu message types) to %s\n", written, hostile.corpora().size(),
              dir.c_str());
  return 0;
}

int Main(int argc, char** argv) {
  common::ArgParser parser("sarmap-decode-fuzz-driver",
                           "Runs the decode fuzz target on the seed corpus, a structured sweep of "
                           "hostile fields, N random hostile datagrams and the given files.");
  int iterations = 20000;
  int64_t seed = 1;
  std::string corpus_dir;
  std::vector<std::string> inputs;
  parser.AddFlag("--iterations", &iterations, "random hostile datagrams to run");
  parser.AddFlag("--seed", &seed, "seed of the random datagrams");
  parser.AddFlag("--write-corpus", &corpus_dir, "write the seed corpus to DIR and exit");
  parser.AddRest("FILE|DIR", &inputs, "inputs to run as well (files, or directories of files)");
  if (!parser.Parse(argc, argv)) return 0;
  if (iterations < 0) throw common::ArgError("--iterations must be >= 0");

  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) signal(sig, OnCrash);
  HostileDatagrams hostile(static_cast<uint64_t>(seed), kNowUtime);
  if (!corpus_dir.empty()) return WriteCorpus(corpus_dir, hostile);

  Counts n;
  int types = 0;
  for (const auto& [name, corpus] : hostile.corpora()) {
    if (corpus.valid.empty()) throw std::runtime_error("no valid sample of " + name);
    ++types;
    for (const Bytes& wire : corpus.valid) Run(name + " seed", wire, &n.corpus);
  }
  const int64_t accepted_seeds = g_accepted_messages;
  for (const auto& [name, corpus] : hostile.corpora()) {
    for (size_t i = 0; i < corpus.valid.size(); ++i) {
      Sweep(name, corpus.valid[i], corpus.fields[i], &n.structured);
    }
  }
  RunRandom(iterations, static_cast<uint64_t>(seed), &hostile, &n.random);
  for (const std::string& path : inputs) {
    for (const std::string& file : InputFiles(path)) {
      Bytes wire;
      if (!ReadFile(file, &wire)) throw std::runtime_error("cannot read " + file);
      Run(file, wire, &n.files);
    }
  }
  const int64_t total = n.corpus + n.structured + n.random + n.files;
  std::printf(
      "decode fuzz: %lld inputs (%lld seeds of %d message types, %lld structured, %lld random, "
      "%lld from files): no crash, no failed check, no oversized allocation; %lld of %lld "
      "message decodes accepted (%lld of the seeds)\n",
      static_cast<long long>(total), static_cast<long long>(n.corpus), types,
      static_cast<long long>(n.structured), static_cast<long long>(n.random),
      static_cast<long long>(n.files), static_cast<long long>(g_accepted_messages),
      static_cast<long long>(g_decoded_messages), static_cast<long long>(accepted_seeds));
  // Every seed is accepted by its own type, at least the sane ones: else the target would
  // only ever exercise rejections.
  if (accepted_seeds < types) {
    std::fprintf(stderr, "decode fuzz: only %lld seeds accepted for %d types\n",
                 static_cast<long long>(accepted_seeds), types);
    return 1;
  }
  return 0;
}

}  // namespace
}  // namespace testing
}  // namespace sarmap

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-decode-fuzz-driver",
                                 [&] { return sarmap::testing::Main(argc, argv); });
}
