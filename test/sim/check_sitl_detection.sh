#!/bin/sh
# motormix's failure detector over the bus (ctest runs it under
# scripts/private-bus): `motormix run` with failure_detection on, beside
# `motormix sim --lcm` whose hexa loses m2 at 11 s with nobody reporting it.
# The simulated vehicle publishes ESC telemetry and attitude. Passes when
# the mixer logged the detection of m2, its status named m2 to the sim (the
# JSON's failure entry), no working motor was declared and the hexa did not
# crash.
#   check_sitl_detection.sh MOTORMIX CONFIG
set -eu
mm=$1
config=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The mixer stops by itself after 15 s of cycles (400 Hz) if nothing else stops it.
"$mm" run --config "$config" --set failure_detection.enabled=true --max-cycles 6000 \
  > "$tmp/run.log" 2>&1 &
mixer=$!
sleep 0.3
code=0
"$mm" sim --config "$config" --scenario steps --lcm --duration 13 --undetected --fail 2@11 \
  --json > "$tmp/sim.json" || code=$?
kill "$mixer" 2>/dev/null || true
wait "$mixer" || true
cat "$tmp/sim.json"
if [ "$code" -ne 0 ] || ! grep -q '"crashed":false' "$tmp/sim.json" ||
  ! grep -q '"detected_motor":"m2"' "$tmp/sim.json" ||
  ! grep -q '"false_detections":0' "$tmp/sim.json" ||
  ! grep -q 'detected motor m2 failed' "$tmp/run.log"; then
  echo "FAILED (exit $code)"
  cat "$tmp/run.log"
  exit 1
fi
grep 'detected motor' "$tmp/run.log"
