#!/usr/bin/env bash
# make demo's live page: runs launch-scripts/demo.sh (a short mission, in its own network
# namespace when it can make one, the page forwarded to this computer's 127.0.0.1), reads the
# page's address from the demo's first lines, waits until the stack has a map, a robot pose and
# a person, then loads the page in headless Chromium while the mission runs: the people table
# lists someone, and the screenshot shows the map (free and unknown cells), the robot and a
# person drawn on the canvas.
#   demo_viewer_test.sh CHROMIUM [SCREENSHOT.png]   (env: SARMAP_BIN_DIR, SARMAP_SOURCE_DIR)
set -euo pipefail
chromium="$1"
keep="${2:-}"
BIN="${SARMAP_BIN_DIR:?SARMAP_BIN_DIR not set}"
SRC="${SARMAP_SOURCE_DIR:?SARMAP_SOURCE_DIR not set}"
out="$(mktemp -d /tmp/sarmap_demo_viewer_test_XXXXXX)"
demo=""
cleanup() {
  [ -z "$demo" ] || kill -INT "$demo" 2>/dev/null || true
  [ -z "$demo" ] || wait "$demo" 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- demo output"; cat "$out/demo.txt" || true; exit 1; }

DEMO_SECONDS="${DEMO_VIEWER_TEST_SECONDS:-45}" DEMO_VIEWER_PORT=0 DEMO_OUT="$out/run" \
  "$SRC/launch-scripts/demo.sh" "$BIN/.." >"$out/demo.txt" 2>&1 &
demo=$!

url=""
for _ in $(seq 300); do
  url="$(sed -nE 's/^== live page while the mission runs: (http[^ ]*).*/\1/p' "$out/demo.txt")"
  [ -n "$url" ] && break
  kill -0 "$demo" 2>/dev/null || fail "the demo ended without printing the page's address"
  sleep 0.2
done
[ -n "$url" ] || fail "no page address in the demo's first lines"
echo "page: $url"

# Until the page's data has a map, the robot and a person (or the mission ends).
ready=""
for _ in $(seq 240); do
  if python3 - "$url" <<'EOF' 2>/dev/null; then ready=1; break; fi
import json, sys, urllib.request
state = json.load(urllib.request.urlopen(sys.argv[1] + "api/state", timeout=2))
sys.exit(0 if state["map"]["available"] and state.get("robot") and state["people"] else 1)
EOF
  kill -0 "$demo" 2>/dev/null || fail "the mission ended before the page showed a map, the robot and a person"
  sleep 0.5
done
[ -n "$ready" ] || fail "no map, robot and person on the page within 120 s"

flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$out/profile" --virtual-time-budget=4000
       --window-size=1280,800)
"$chromium" "${flags[@]}" --dump-dom "$url" >"$out/dom.html" 2>"$out/chromium.log" || fail "chromium --dump-dom failed"
grep -Eq '<td style="color:[^"]*">(seen|heard|both)' "$out/dom.html" \
  || fail "the rendered page's people table lists nobody: $(grep -o '<table id="people">.\{0,300\}' "$out/dom.html")"
# The colours on the map canvas, checked by check_screenshot.py below (components/viewer/web/index.html):
# map cells unknown (grey 205) and free or nearly (greys 215-255: 255 - 255 * occupancy / 100),
# the robot (#ecf0f1), people seen (#2ecc71), heard (#e74c3c) or both (#f1c40f).
cat >"$out/check_screenshot.py" <<'EOF'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n"
pos, idat, width, height, channels = 8, b"", 0, 0, 0
while pos < len(data):
    length, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + length]
    if kind == b"IHDR":
        width, height, depth, colour_type = struct.unpack(">IIBB", body[:10])
        assert depth == 8 and colour_type in (2, 6), "unexpected PNG format"
        channels = 3 if colour_type == 2 else 4
    elif kind == b"IDAT":
        idat += body
    pos += 12 + length
raw = zlib.decompress(idat)
stride = width * channels
rows, prev = [], bytearray(stride)
for y in range(height):
    f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a = line[i - channels] if i >= channels else 0
        b, c = prev[i], prev[i - channels] if i >= channels else 0
        if f == 1: line[i] = (line[i] + a) & 255
        elif f == 2: line[i] = (line[i] + b) & 255
        elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line)
    prev = line
# Only the map canvas: left of the side panel (70 % of the 1280 px window), below the header;
# the legend and the people table use the people's colours too.
counts = {}
for line in rows[45:]:
    for i in range(0, int(0.7 * width) * channels, channels):
        key = bytes(line[i:i + 3])
        counts[key] = counts.get(key, 0) + 1
def n(hex_colour):
    return counts.get(bytes.fromhex(hex_colour), 0)
free = sum(counts.get(bytes([g, g, g]), 0) for g in range(215, 256))
found = {"free cells": free, "unknown cells": n("cdcdcd"), "robot": n("ecf0f1"),
         "people": n("2ecc71") + n("e74c3c") + n("f1c40f")}
print("screenshot pixels:", ", ".join("%s %d" % kv for kv in found.items()))
need = {"free cells": 500, "unknown cells": 500, "robot": 20, "people": 20}
missing = [k for k, v in need.items() if found[k] < v]
if missing:
    print("missing:", ", ".join(missing))
    sys.exit(1)
EOF
# A loaded machine may draw the first MAP late: up to three screenshots, a few seconds apart.
drawn=""
for attempt in 1 2 3; do
  "$chromium" "${flags[@]}" --screenshot="$out/page.png" "$url" 2>>"$out/chromium.log" || fail "chromium --screenshot failed"
  kill -0 "$demo" 2>/dev/null || fail "the mission had ended when the page was loaded"
  if python3 "$out/check_screenshot.py" "$out/page.png"; then drawn=1; break; fi
  sleep 3
done
[ -z "$keep" ] || cp "$out/page.png" "$keep"
[ -n "$drawn" ] || fail "the screenshot lacks the map, the robot or a person"
echo "the live page during the mission, in headless Chromium: map, robot and a person drawn"
wait "$demo" || fail "demo.sh exited with $?"
demo=""
grep -q "demo finished" "$out/demo.txt" || fail "the demo did not finish"
echo "PASS"
