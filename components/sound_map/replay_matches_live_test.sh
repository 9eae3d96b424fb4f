#!/usr/bin/env bash
# A mission's sound log replayed through sarmap-sound-map's adapter publishes the live map
# again: sarmap-mission-bench runs a 60 s search of the open-area world with the sound chain
# in process and logs the sound map's inputs; sarmap-log-sound-map replays them through
# SoundMapNode and compares every SOUND_MAP it publishes with the live one at the same time.
# The replayed map written to a log (--write-map) and given to the people map's replay
# (sarmap-log-people-map --sound-map) gives the people map the live SOUND_MAP gave it.
set -euo pipefail
bin="${SARMAP_BIN_DIR:?}"; src="${SARMAP_SOURCE_DIR:?}"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
cd "$src"
"$bin/sarmap-mission-bench" --worlds config/worlds/open_area_sound.yaml --modes frontier \
  --duration 60 --camera-rate 1 --sound-log --people-log --out "$tmp" > "$tmp/bench.txt" 2>&1 ||
  { cat "$tmp/bench.txt"; exit 1; }
log="$tmp/open_area_sound-frontier-sound.lcmlog"
"$bin/sarmap-log-sound-map" "$log" --write-map "$tmp/map.lcmlog" > "$tmp/replay.txt" 2> "$tmp/replay.err" ||
  { cat "$tmp/replay.txt" "$tmp/replay.err"; exit 1; }
cat "$tmp/replay.txt"
line="$(grep "the replay published at" "$tmp/replay.txt")"
# "the replay published at N of the live node's M times: the same sources within 1 mm at K"
read -r n m k < <(echo "$line" | sed -E 's/.*published at ([0-9]+) of the live node.s ([0-9]+) times.* at ([0-9]+).*/\1 \2 \3/')
echo "compared $n of $m live maps, identical $k"
[ "$m" -ge 100 ] || { echo "FAIL: only $m live SOUND_MAPs"; exit 1; }
# The in-process mission answers an anchor request at once, inside the map's update, which can
# move when a SOUND_MAP falls due; what is published at a common time must be the same.
[ $((2 * n)) -ge "$m" ] || { echo "FAIL: the replay published at only $n of the live node's $m times"; exit 1; }
[ "$k" -eq "$n" ] || { echo "FAIL: the replay's map differs from the live one at $((n - k)) times"; exit 1; }
people="$tmp/open_area_sound-frontier-people.lcmlog"
"$bin/sarmap-log-people-map" "$people" > "$tmp/people_live.txt" 2>&1 ||
  { cat "$tmp/people_live.txt"; exit 1; }
"$bin/sarmap-log-people-map" "$people" --sound-map "$tmp/map.lcmlog" > "$tmp/people_replayed.txt" 2>&1 ||
  { cat "$tmp/people_replayed.txt"; exit 1; }
maps="$(sed -nE 's/.* ([0-9]+) SOUND_MAP from .*/\1/p' "$tmp/people_replayed.txt")"
[ "${maps:-0}" -gt 0 ] || { echo "FAIL: the people map took no replayed SOUND_MAP"; cat "$tmp/people_replayed.txt"; exit 1; }
live_people="$(grep -E "^(found|person )" "$tmp/people_live.txt")"
replayed_people="$(grep -E "^(found|person )" "$tmp/people_replayed.txt")"
echo "people map with the live SOUND_MAP (and with $maps replayed ones):"; echo "$live_people"
[ -n "$live_people" ] || { echo "FAIL: no people-map report"; cat "$tmp/people_live.txt"; exit 1; }
[ "$live_people" = "$replayed_people" ] ||
  { echo "FAIL: with the replayed SOUND_MAP the people map differs:"; echo "$replayed_people"; exit 1; }
echo PASS
