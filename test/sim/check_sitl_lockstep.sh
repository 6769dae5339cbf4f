#!/bin/sh
# The spin landing over the bus in lockstep (docs/lockstep.md; ctest runs it
# under scripts/private-bus): `motormix run --lockstep` with a quad X beside
# `motormix sim --lcm --lockstep`, a CPU hog on every core the whole time
# (bounded), with the configuration's own timing (attitude_timeout_ms 50).
# Five flights: motor 1 stopping at 8 s at 10 m found by the mixer's own
# detector, reported on motor_status 100 ms later, motors 1 and 2 together,
# a thrown prop, a broken prop tip. Each passes when the quad did not crash,
# touched down no faster than 2 m/s, and the mixer logged taking over and
# disarming on touchdown. Then the first flight again: lockstep is
# deterministic, so its result is the same to the last digit (but the wall
# time it took).
#   check_sitl_lockstep.sh MOTORMIX CONFIG
set -eu
mm=$1
config=$2
tmp=$(mktemp -d)
. "$(dirname "$0")/cpu_hogs.sh"
trap 'stop_hogs; rm -rf "$tmp"' EXIT
start_hogs 280  # the test's own timeout is 300 s
failed=0
# fly NAME EXPECTED-LOG-LINE [SIM ARGS...]
fly() {
  name=$1
  expected=$2
  shift 2
  # Bounded by itself too: 28 s of ticks at 400 Hz.
  "$mm" run --config "$config" --lockstep --set failure_detection.enabled=true \
    --max-cycles 11200 > "$tmp/run.log" 2>&1 &
  mixer=$!
  sleep 0.3
  code=0
  "$mm" sim --config "$config" --scenario spin_landing --lcm --lockstep --duration 26 --json \
    "$@" > "$tmp/sim.json" || code=$?
  kill "$mixer" 2>/dev/null || true
  wait "$mixer" || true
  echo "== $name"
  cat "$tmp/sim.json"
  speed=$(sed -n 's/.*"touchdown_speed_mps":\([0-9.e+-]*\).*/\1/p' "$tmp/sim.json")
  if [ "$code" -ne 0 ] || ! grep -q '"crashed":false' "$tmp/sim.json" || [ -z "$speed" ] ||
    ! awk -v s="$speed" 'BEGIN { exit !(s <= 2.0) }' ||
    ! grep -q "$expected" "$tmp/run.log" ||
    ! grep -q 'spin landing touched down: disarmed' "$tmp/run.log"; then
    echo "FAILED $name (exit $code, touchdown at ${speed:-no} m/s)"
    cat "$tmp/run.log"
    failed=1
    return
  fi
  grep 'spin landing\|landing spinning\|lockstep' "$tmp/run.log"
}
fly "found by the detector" 'landing spinning on the other three' --undetected
# Without the wall-clock fields, kept for the comparison below.
strip() { sed 's/"realtime_factor":[^,}]*//; s/"wall_seconds":[^,}]*//' "$1"; }
strip "$tmp/sim.json" > "$tmp/first.json"
fly "reported after 100 ms" 'landing spinning on the other three'
fly "two opposite motors, found by the detector" 'landing spinning on the other two' \
  --undetected --no-scenario-failures --fail 1@8 --fail 2@8
fly "a thrown prop, found by the detector" 'landing spinning on the other three' \
  --undetected --no-scenario-failures --fail 1@8:prop_lost
fly "a broken prop tip, found by the detector" 'landing spinning on the other three' \
  --undetected --no-scenario-failures --fail 1@8:prop_damaged
fly "found by the detector, again" 'landing spinning on the other three' --undetected
strip "$tmp/sim.json" > "$tmp/again.json"
if ! cmp -s "$tmp/first.json" "$tmp/again.json"; then
  echo "FAILED: the same flight in lockstep gave another result"
  diff "$tmp/first.json" "$tmp/again.json" || true
  failed=1
fi
# A simulator gone: the mixer stops by itself once no tick has come for
# --lockstep-idle-s, with status 3 (bounded here to 10 s all the same).
# Both started at once: the simulator repeats its first tick until the
# mixer, still starting, answers it.
"$mm" run --config "$config" --lockstep --lockstep-idle-s 1 > "$tmp/idle.log" 2>&1 &
mixer=$!
"$mm" sim --config "$config" --scenario hover --lcm --lockstep --duration 2 --json \
  > "$tmp/idle.json" || true
waited=0
while kill -0 "$mixer" 2>/dev/null && [ "$waited" -lt 40 ]; do
  sleep 0.25
  waited=$((waited + 1))
done
kill "$mixer" 2>/dev/null || true
code=0
wait "$mixer" || code=$?
echo "== simulator gone: the mixer exited $code after $waited quarter seconds"
if [ "$code" -ne 3 ] || ! grep -q 'no tick for 1 s: the simulator is gone' "$tmp/idle.log" ||
  ! grep -q '"crashed":false' "$tmp/idle.json" || ! grep -q '"lockstep_lost":false' "$tmp/idle.json" ||
  ! grep -q 'lockstep: 800 ticks run' "$tmp/idle.log"; then
  echo "FAILED: a lockstep mixer whose simulator stopped did not stop by itself"
  cat "$tmp/idle.log"
  failed=1
fi
exit $failed
