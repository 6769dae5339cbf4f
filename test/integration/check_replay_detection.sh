#!/bin/sh
# Flights replayed offline through a hexa X and an octo X with the failure
# detector's outputs source (the one source a log without ESC telemetry or
# attitude can feed): no motor may be declared. The bundled flights (the
# team quad's on its own channel names), and healthy flights the simulator
# records here (steps, gusts, flips, battery_sag on three seeds: the long healthy run the
# bundled flights do not give). Every replay must have flown: armed at
# least MIN_ARMED_S, and the armed seconds per vehicle are summed and
# bounded below, so a replay that takes no input cannot pass.
#   check_replay_detection.sh MOTORMIX SOURCE_DIR
set -eu
mm=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
MIN_ARMED_S=4
MIN_TOTAL_ARMED_S=200
status=0
logs=""
for flight in team_quad flips dropout battery_sag hexa_motor_out; do
  logs="$logs $src/test/data/flights/$flight.lcmlog"
done
for scenario in steps gusts flips battery_sag; do
  for seed in 1 2 3; do
    "$mm" sim --config "$src/config/hexa_x.yaml" --scenario "$scenario" --seed "$seed" \
      --log "$tmp/sim_${scenario}_$seed.lcmlog" --json > /dev/null
    logs="$logs $tmp/sim_${scenario}_$seed.lcmlog"
  done
done
for vehicle in hexa_x octo_x; do
  total=0
  for log in $logs; do
    name=$(basename "$log" .lcmlog)
    channels=""
    # The team quad's flight is on its own channel names.
    [ "$name" = team_quad ] && channels="--set channels.setpoint=pos_deseada --set channels.pid=pid"
    # shellcheck disable=SC2086
    "$mm" replay --config "$src/config/$vehicle.yaml" --set 'failure_detection.sources=[outputs]' \
      --set inputs.yaw_source=setpoint $channels "$log" "$tmp/out.lcmlog" > "$tmp/summary.txt" 2>&1
    line=$(grep 'declared by the failure detector' "$tmp/summary.txt")
    armed=$(sed -n 's/^armed *\([0-9.]*\) s.*/\1/p' "$tmp/summary.txt")
    echo "$name / $vehicle: armed ${armed:-?} s; $line"
    case "$line" in
      *", 0 declared by the failure detector") ;;
      *) status=1 ;;
    esac
    if ! awk -v a="${armed:-0}" -v m="$MIN_ARMED_S" 'BEGIN { exit !(a >= m) }'; then
      echo "  armed less than $MIN_ARMED_S s: the replay took no flight" >&2
      status=1
    fi
    total=$(awk -v t="$total" -v a="${armed:-0}" 'BEGIN { print t + a }')
  done
  echo "$vehicle: $total armed seconds replayed"
  if ! awk -v t="$total" -v m="$MIN_TOTAL_ARMED_S" 'BEGIN { exit !(t >= m) }'; then
    echo "  fewer than $MIN_TOTAL_ARMED_S armed seconds" >&2
    status=1
  fi
done
exit $status
