#!/usr/bin/env bash
# Multi-card array end to end (inside sarmap-netns): async_array_wavgen writes three cards'
# recordings of one source (az 47.3, el 20) with injected start offsets (+1.3 / -0.7 ms) and clock
# drifts (+80 / -120 ppm); three sarmap-audio-capture processes, one per card, publish them on
# AUDIO_CARD0..2 with their own sample counters; sarmap-sound-localisation (devices / mic_devices)
# aligns the streams with the array's calibrated offsets and drifts and publishes DOA over real
# LCM; sarmap-log record records; the median direction must be within 2 deg of the truth.
# A second localiser on the same streams with the offsets and drifts zeroed shows that they
# matter (reported, not asserted: an unaligned array may still point somewhere).
set -euo pipefail
bin="${SARMAP_BIN_DIR:?}"; src="${SARMAP_SOURCE_DIR:?}"
tmp="$(mktemp -d)"; trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$tmp"' EXIT
cd "$src"
"$bin/async_array_wavgen" "$tmp" 6
sed -e 's/^start_offsets_s:.*/start_offsets_s: [0.0, 0.0, 0.0, 0.0]/' -e 's/^clock_drift:.*/clock_drift: [0.0, 0.0, 0.0, 0.0]/' \
  "$tmp/array.yaml" > "$tmp/array_unaligned.yaml"
"$bin/sarmap-log-record" -q -o "$tmp/log.lcm" & logger=$!
async=(--set devices=[card0,card1,card2] --set mic_devices=[0,0,1,2]
       --set audio_channels=[AUDIO_CARD0,AUDIO_CARD1,AUDIO_CARD2])
"$bin/sarmap-sound-localisation" --config config/sound_localisation.yaml --set array="$tmp/array.yaml" "${async[@]}" \
  > "$tmp/loc.txt" 2>&1 & loc=$!
"$bin/sarmap-sound-localisation" --config config/sound_localisation.yaml --set array="$tmp/array_unaligned.yaml" \
  "${async[@]}" --set doa_channel=DOA_UNALIGNED > "$tmp/loc_unaligned.txt" 2>&1 & loc2=$!
sleep 1
caps=()
for c in 0 1 2; do
  "$bin/sarmap-audio-capture" --config config/audio_capture.yaml --file "$tmp/card$c.wav" --speed 1 \
    --set device_id=card$c --set channel=AUDIO_* --set num_channels=0 > "$tmp/cap$c.txt" 2>&1 & caps+=($!)
done
wait "${caps[@]}"
sleep 1.5
kill -INT $loc $loc2 $logger 2>/dev/null || true
wait $loc $loc2 $logger 2>/dev/null || true
for c in 0 1 2; do echo "--- capture card$c"; cat "$tmp/cap$c.txt"; done
echo "--- localisation (aligned)"; cat "$tmp/loc.txt"
echo "--- localisation (offsets and drifts zeroed)"; cat "$tmp/loc_unaligned.txt"
echo "--- unaligned (for comparison, not asserted)"
"$bin/doa_log_check" "$tmp/log.lcm" 47.3 20 2 10 DOA_UNALIGNED || true
echo "--- aligned"
"$bin/doa_log_check" "$tmp/log.lcm" 47.3 20 2 10 DOA
