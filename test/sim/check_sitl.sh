#!/bin/sh
# Software in the loop on a private bus (ctest runs it under
# scripts/private-bus): a live `motormix run` and `motormix sim --lcm` as two
# processes, 10 s of each scenario given, in real time. Passes when the
# vehicle did not crash, flew on the mixer's armed outputs (armed_s: the
# time the sim's motors ran on fresh, armed motor_pwm_t from the bus) and
# climbed to the commanded altitude (reached_altitude): a vehicle left on
# the ground by a broken arming does not crash either.
#   check_sitl.sh MOTORMIX CONFIG SCENARIO...
set -eu
mm=$1
config=$2
shift 2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
status=0
for scenario in "$@"; do
  # The mixer stops by itself after 12 s of cycles (400 Hz) if nothing else stops it.
  "$mm" run --config "$config" --max-cycles 4800 > "$tmp/run.log" 2>&1 &
  mixer=$!
  sleep 0.3
  code=0
  "$mm" sim --config "$config" --scenario "$scenario" --lcm --duration 10 --json > "$tmp/sim.json" || code=$?
  kill "$mixer" 2>/dev/null || true
  wait "$mixer" || true
  echo "$scenario: $(cat "$tmp/sim.json")"
  received=$(sed -n 's/.*"pwm_received":\([0-9]*\).*/\1/p' "$tmp/sim.json")
  armed=$(sed -n 's/.*"armed_s":\([0-9.]*\).*/\1/p' "$tmp/sim.json")
  # Armed for at least 8 of the 10 s (measured: 9.5 s; the arming takes
  # half a second), as the sim saw the outputs on the bus.
  if [ "$code" -ne 0 ] || ! grep -q '"crashed":false' "$tmp/sim.json" ||
    ! grep -q '"reached_altitude":true' "$tmp/sim.json" ||
    ! awk -v a="${armed:-0}" 'BEGIN { exit !(a >= 8.0) }'; then
    echo "FAILED: $scenario (exit $code, $received outputs from the mixer, armed ${armed:-0} s)"
    cat "$tmp/run.log"
    status=1
  fi
done
exit $status
