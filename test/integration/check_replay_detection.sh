#!/bin/sh
# The bundled flights, replayed offline through a hexa X and an octo X with
# the failure detector's outputs source (the one source a log without ESC
# telemetry or attitude can feed): no motor may be declared.
#   check_replay_detection.sh MOTORMIX SOURCE_DIR
set -eu
mm=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
status=0
for flight in team_quad flips dropout battery_sag hexa_motor_out; do
  for vehicle in hexa_x octo_x; do
    "$mm" replay --config "$src/config/$vehicle.yaml" --set 'failure_detection.sources=[outputs]' \
      --set inputs.yaw_source=setpoint "$src/test/data/flights/$flight.lcmlog" "$tmp/out.lcmlog" \
      > "$tmp/summary.txt" 2>&1
    line=$(grep 'declared by the failure detector' "$tmp/summary.txt")
    echo "$flight / $vehicle: $line"
    case "$line" in
      *", 0 declared by the failure detector") ;;
      *) status=1 ;;
    esac
  done
done
exit $status
