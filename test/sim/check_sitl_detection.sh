#!/bin/sh
# motormix's failure detector over the bus (ctest runs it under
# scripts/private-bus), in lockstep (docs/lockstep.md) with a CPU hog on
# every core: `motormix run --lockstep` with failure_detection on (telemetry
# and rates), beside `motormix sim --lcm --lockstep` whose hexa loses a motor at 11 s
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
. "$(dirname "$0")/cpu_hogs.sh"
trap 'stop_hogs; rm -rf "$tmp"' EXIT
start_hogs 110  # the test's own timeout is 120 s
# detection_sim_tests holds telemetry to 100 ms in lockstep, and so does
# this over the bus in lockstep: the simulator reads the declaration's time
# from the mixer's status stamp, simulated time. (In real time it was
# 0.25 s: the status period and the machine's stalls counted too.)
MAX_LATENCY_S=0.1
status=0
for motor in 2 5; do
  # The mixer stops by itself after 15 s of cycles (400 Hz) if nothing else stops it.
  "$mm" run --config "$config" --lockstep --set failure_detection.enabled=true \
    --set 'failure_detection.sources=[telemetry, rates]' --max-cycles 6000 \
    > "$tmp/run.log" 2>&1 &
  mixer=$!
  sleep 0.3
  code=0
  "$mm" sim --config "$config" --scenario steps --lcm --lockstep --duration 13 --undetected \
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
