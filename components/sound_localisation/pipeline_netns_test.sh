#!/usr/bin/env bash
# Multi-process test (inside sarmap-netns): sarmap-audio-capture plays a real ReSpeaker recording
# (talker at azimuth 180, elevation 20) on AUDIO; sarmap-sound-localisation publishes DOA;
# sarmap-speech listens; sarmap-log record records; the log must hold tracked DOAs near the truth.
set -euo pipefail
bin="${SARMAP_BIN_DIR:?}"; src="${SARMAP_SOURCE_DIR:?}"; data="${SARMAP_DATA_DIR:?}"
wav="$data/audio/respeaker4/a180e20/50cm/a180e19_3_1b6ede00.wav"
if [ ! -f "$wav" ]; then echo "shared data missing: $wav (skipped)"; exit 0; fi
tmp="$(mktemp -d)"; trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$tmp"' EXIT
cd "$src"
"$bin/sarmap-log-record" -q -o "$tmp/log.lcm" & logger=$!
"$bin/sarmap-sound-localisation" --config config/sound_localisation.yaml > "$tmp/loc.txt" 2>&1 & loc=$!
"$bin/sarmap-speech" --config config/speech.yaml > "$tmp/speech.txt" 2>&1 & sp=$!
sleep 3   # the speech node loads PocketSphinx
"$bin/sarmap-audio-capture" --config config/audio_capture.yaml --file "$wav" --speed 2 > "$tmp/cap.txt" 2>&1
sleep 2
kill -INT $loc $sp $logger 2>/dev/null || true
wait $loc $sp $logger 2>/dev/null || true
echo "--- capture"; cat "$tmp/cap.txt"; echo "--- localisation"; cat "$tmp/loc.txt"; echo "--- speech"; cat "$tmp/speech.txt"
"$bin/doa_log_check" "$tmp/log.lcm" 180 20 5 20
