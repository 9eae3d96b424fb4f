#!/usr/bin/env bash
# make fuzz: the decode fuzz target under libFuzzer (clang, AddressSanitizer, UBSan) for
# FUZZ_SECONDS, then its corpus replayed through the g++ build of the same target.
#
#   tests/fuzz/run_libfuzzer.sh BUILD_DIR FUZZ_DIR SECONDS
#
# BUILD_DIR is the normal build (for sarmap-decode-fuzz-driver, which writes the seed corpus:
# valid encodings of every message type). FUZZ_DIR is configured with clang-14 and
# -DSARMAP_LIBFUZZER=ON on first use; FUZZ_DIR/corpus keeps what libFuzzer found between runs,
# and a crash, out-of-memory or timeout input is written to FUZZ_DIR/crashes/.
set -euo pipefail
build="${1:?usage: run_libfuzzer.sh BUILD_DIR FUZZ_DIR SECONDS}"
fuzz="${2:?usage: run_libfuzzer.sh BUILD_DIR FUZZ_DIR SECONDS}"
seconds="${3:?usage: run_libfuzzer.sh BUILD_DIR FUZZ_DIR SECONDS}"
root="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$root"

command -v clang++-14 >/dev/null || { echo "fuzz: clang++-14 is missing (make deps installs it)"; exit 1; }
cmake --build "$build" --target sarmap-decode-fuzz-driver
if [ ! -f "$fuzz/build.ninja" ]; then
  CC=clang-14 CXX=clang++-14 cmake -S . -B "$fuzz" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSARMAP_LIBFUZZER=ON
fi
cmake --build "$fuzz" --target sarmap-decode-fuzz
mkdir -p "$fuzz/seeds" "$fuzz/corpus" "$fuzz/crashes"
"$build/bin/sarmap-decode-fuzz-driver" --write-corpus "$fuzz/seeds"

# -malloc_limit_mb: above the largest buffer a checked message may legitimately ask for (a
# compressed 2^28-cell occupancy grid decompresses to 256 MiB), far below a count read as
# gigabytes. -max_len: LCM's datagrams are fragmented above 64 kB; the decoders see the whole
# message, but 64 kB already holds every field of every type many times.
echo "== libFuzzer for ${seconds} s (sarmap-decode-fuzz, every message type)"
status=0
"$fuzz/bin/sarmap-decode-fuzz" -max_total_time="$seconds" -max_len=65536 -malloc_limit_mb=300 \
  -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 -artifact_prefix="$fuzz/crashes/" \
  "$fuzz/corpus" "$fuzz/seeds" 2>"$fuzz/libfuzzer.log" || status=$?
grep -E "^(INFO: Seed|#[0-9]+[[:space:]]+(INITED|DONE))|^stat::|ERROR|SUMMARY|Test unit written" \
  "$fuzz/libfuzzer.log" || true
if [ "$status" != 0 ]; then
  echo "fuzz: libFuzzer found a problem (exit $status); the log is $fuzz/libfuzzer.log, the input in $fuzz/crashes/"
  tail -n 40 "$fuzz/libfuzzer.log"
  exit 1
fi
echo "== the corpus through the g++ build (sarmap-decode-fuzz-driver)"
"$build/bin/sarmap-decode-fuzz-driver" --iterations 0 "$fuzz/corpus"
echo "fuzz: $(ls "$fuzz/corpus" | wc -l) inputs in $fuzz/corpus, no finding"
