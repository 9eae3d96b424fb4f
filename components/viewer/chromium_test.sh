#!/usr/bin/env bash
# Loads the viewer page in headless Chromium against sarmap-viewer-demo: checks that the
# JavaScript fetched the state and rendered it (people table in the DOM), and takes a
# screenshot; then that markup in keywords and deputy/command names is shown as text and
# never runs.  chromium_test.sh CHROMIUM VIEWER_DEMO SCREENSHOT.png
set -euo pipefail
chromium="$1"; demo="$2"; shot="$3"
work="$(mktemp -d)"
trap 'kill $pid 2>/dev/null || true; rm -rf "$work"' EXIT
"$demo" --seconds 60 --token test-token-123 > "$work/demo.txt" &
pid=$!
for _ in $(seq 100); do grep -q "^port" "$work/demo.txt" && break; sleep 0.1; done
port=$(awk '/^port/{print $2}' "$work/demo.txt")
url="http://127.0.0.1:$port/?token=test-token-123"
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile" --virtual-time-budget=4000
       --window-size=1280,800)
"$chromium" "${flags[@]}" --dump-dom "$url" > "$work/dom.html" 2> "$work/chromium.log"
for want in 'heard</td>' 'both</td>' 'sarmap-slam' '>help<' 'respawning' 'seeking sound'; do
  if ! grep -q "$want" "$work/dom.html"; then
    echo "FAIL: rendered page lacks '$want'"; tail -5 "$work/chromium.log"; exit 1
  fi
done
"$chromium" "${flags[@]}" --screenshot="$shot" "$url" 2>> "$work/chromium.log"
kill $pid 2>/dev/null || true; wait $pid 2>/dev/null || true

# Markup from the bus (a keyword, deputy and command names) is shown as text; nothing runs.
"$demo" --seconds 60 --token test-token-123 --hostile > "$work/hostile.txt" &
pid=$!
for _ in $(seq 100); do grep -q "^port" "$work/hostile.txt" && break; sleep 0.1; done
port=$(awk '/^port/{print $2}' "$work/hostile.txt")
"$chromium" "${flags[@]}" --dump-dom "http://127.0.0.1:$port/?token=test-token-123" > "$work/hostile.html" 2>> "$work/chromium.log"
if grep -q 'data-pwned' "$work/hostile.html"; then
  echo "FAIL: markup from the bus ran in the page: $(grep -o 'data-pwned="[^"]*"' "$work/hostile.html")"; exit 1
fi
for want in '&lt;img src=x onerror=' '&lt;script&gt;document.body' '&lt;img src=y onerror=' '&lt;img src=z onerror='; do
  if ! grep -qF "$want" "$work/hostile.html"; then
    echo "FAIL: the page does not show '$want' as text"; tail -5 "$work/chromium.log"; exit 1
  fi
done
echo "markup in keywords and process names shown as text, not run"
size=$(stat -c %s "$shot")
if [ "$size" -lt 20000 ]; then echo "FAIL: screenshot suspiciously small ($size bytes)"; exit 1; fi
echo "viewer rendered in headless Chromium; screenshot $shot ($size bytes)"
