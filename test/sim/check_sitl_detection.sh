#!/bin/sh
# motormix's failure detector over the bus (ctest runs it under
# scripts/private-bus): `motormix run` with failure_detection on (telemetry
# and rates), beside `motormix sim --lcm` whose hexa loses a motor at 11 s
# with nobody reporting it, twice: m2, then m5 (a detector that always names
# one motor fails one of them). The simulated vehicle publishes ESC
# telemetry and attitude. Passes when, each time: the mixer logged the
# detection of that motor; its status named that motor to the sim, by the
# telemetry source (the faster one, which a mixer that never heard the
# telemetry would not name), within MAX_LATENCY_S of the failure; only one
# motor was declared, no working one; and the hexa did not crash.
#   check_sitl_detection.sh MOTORMIX CONFIG
set -eu
mm=$1
config=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# detection_sim_tests holds telemetry to 100 ms in lockstep; over the bus
# the status that reports it adds up to its period (100 ms at 10 Hz).
MAX_LATENCY_S=0.25
status=0
for motor in 2 5; do
  # The mixer stops by itself after 15 s of cycles (400 Hz) if nothing else stops it.
  "$mm" run --config "$config" --set failure_detection.enabled=true \
    --set 'failure_detection.sources=[telemetry, rates]' --max-cycles 6000 \
    > "$tmp/run.log" 2>&1 &
  mixer=$!
  sleep 0.3
  code=0
  "$mm" sim --config "$config" --scenario steps --lcm --duration 13 --undetected \
    --fail "$motor@11" --json > "$tmp/sim.json" || code=$?
  kill "$mixer" 2>/dev/null || true
  wait "$mixer" || true
  cat "$tmp/sim.json"
  if [ "$code" -ne 0 ] || ! grep -q "detected motor m$motor failed (telemetry)" "$tmp/run.log" ||
    ! python3 - "$tmp/sim.json" "m$motor" "$MAX_LATENCY_S" <<'PY'
import json, sys
j = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
motor, bound = sys.argv[2], float(sys.argv[3])
f = j["failures"][0]
ok = (not j["crashed"] and j["false_detections"] == 0 and len(j["detections"]) == 1
      and f["detected_motor"] == motor and f["detected_by"] == "telemetry"
      and f["detected_at_s"] is not None and 0 <= f["detected_at_s"] - f["at_s"] <= bound)
print(f"{motor}: detected {f['detected_motor']} by {f['detected_by']} "
      f"{(f['detected_at_s'] or -1) - f['at_s']:.3f} s after the failure; "
      f"{len(j['detections'])} declaration(s), {j['false_detections']} false")
sys.exit(0 if ok else 1)
PY
  then
    echo "FAILED for m$motor (exit $code)"
    cat "$tmp/run.log"
    status=1
  fi
done
exit $status
