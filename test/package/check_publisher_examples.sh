#!/usr/bin/env bash
# The example publishers of attitude_t and esc_telemetry_t
# (examples/publishers) feed a running `motormix run` whose failure detector
# reads both (quad X, sources telemetry and rates, spin landing on): the
# mixer accepts their messages and `motormix monitor --once` shows both
# inputs fresh. First the C++ publishers, then, with LCM's Python bindings,
# the Python ones (after the C++ ones stopped, so the ages they leave are
# old). The Python frame conversion is checked against rotation matrices.
# Then the Python ones again with the bus key (--key) against a mixer that
# requires signatures: taken, verified, none refused.
#   scripts/private-bus check_publisher_examples.sh MOTORMIX ATTITUDE_CPP ESC_CPP SOURCE_DIR \
#     PYTHON_TYPES_DIR WORKDIR [PYTHON]
# Exit 77: the Python publishers could not be run (no bindings).
set -euo pipefail
if [ "${MOTORMIX_PRIVATE_BUS:-}" != "1" ]; then echo "run through scripts/private-bus" >&2; exit 2; fi
motormix="$1" attitude_cpp="$2" esc_cpp="$3" src="$4" types="$5" work="$6" python="${7:-}"
fail() { echo "check_publisher_examples: FAIL: $*" >&2; exit 1; }
rm -rf "$work" && mkdir -p "$work"
config=(--config "$src/config/quad_x.yaml" --set 'failure_detection.sources=[telemetry, rates]')

# Bounded: 30 s at 400 Hz if nothing else stops it.
"$motormix" run "${config[@]}" --max-cycles 12000 2> "$work/run.log" &
mixer=$!
trap 'kill "$mixer" 2>/dev/null || true' EXIT
sleep 0.5

# fresh NAME: the monitor's feeds line shows both inputs younger than
# FRESH_MS, and the accepted counts are positive.
FRESH_MS=250
fresh() {
  "$motormix" monitor "${config[@]}" --once --wait 5 > "$work/$1.monitor.txt" \
    || fail "$1: no status"
  local feeds
  feeds=$(grep '^feeds ' "$work/$1.monitor.txt") || fail "$1: no feeds line"
  echo "$1: $feeds"
  case "$feeds" in *"NOT FED"*) fail "$1: $feeds" ;; esac
  local esc attitude
  esc=$(sed -n 's/.*esc_telemetry \([0-9]*\) ms.*/\1/p' <<< "$feeds")
  attitude=$(sed -n 's/.*attitude \([0-9]*\) ms.*/\1/p' <<< "$feeds")
  [ -n "$esc" ] && [ "$esc" -lt "$FRESH_MS" ] || fail "$1: esc_telemetry not fresh: $feeds"
  [ -n "$attitude" ] && [ "$attitude" -lt "$FRESH_MS" ] || fail "$1: attitude not fresh: $feeds"
  grep -Eq 'esc_telemetry [1-9][0-9]*   attitude [1-9]' "$work/$1.monitor.txt" \
    || fail "$1: nothing accepted: $(grep '^accepted' "$work/$1.monitor.txt")"
}

"$attitude_cpp" --rate-hz 500 --count 1500 &
att=$!
"$esc_cpp" --motors 4 --rate-hz 200 --count 600 &
esc=$!
sleep 1.5
fresh cpp
wait "$att" || fail "the C++ attitude publisher failed"
wait "$esc" || fail "the C++ ESC publisher failed"
grep -q "rejected" "$work/run.log" && fail "the mixer logged rejections: $(grep rejected "$work/run.log")"

status=0
if [ -n "$python" ] && PYTHONPATH="$types" "$python" -c 'import lcm, motormix' 2> /dev/null; then
  PYTHONPATH="$src/examples/publishers" "$python" - <<'PY' || fail "frames.py disagrees with the rotation matrices"
import math, random
import frames

def matrix(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]

def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]

NED_FROM_ENU = [[0, 1, 0], [1, 0, 0], [0, 0, -1]]
FLU_FROM_FRD = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
TOLERANCE = 1e-12
rng = random.Random(7)
for _ in range(200):
    q = [rng.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(c * c for c in q))
    q = [c / n for c in q]
    expected = mul(mul(NED_FROM_ENU, matrix(q)), FLU_FROM_FRD)
    got = matrix(frames.frd_ned_from_flu_enu(q))
    assert all(abs(expected[i][j] - got[i][j]) < TOLERANCE for i in range(3) for j in range(3))
    v = [rng.gauss(0, 1) for _ in range(3)]
    ned = [sum(NED_FROM_ENU[i][k] * v[k] for k in range(3)) for i in range(3)]
    assert all(abs(a - b) < TOLERANCE for a, b in zip(ned, frames.ned_from_enu(v)))
    frd = [sum(FLU_FROM_FRD[k][i] * v[k] for k in range(3)) for i in range(3)]
    assert all(abs(a - b) < TOLERANCE for a, b in zip(frd, frames.frd_from_flu(v)))
print("frames.py: 200 random attitudes, velocities and rates match the matrices")
PY
  sleep 1  # the C++ publishers' ages grow old
  PYTHONPATH="$types" "$python" "$src/examples/publishers/attitude_publisher.py" --rate-hz 500 \
    --count 1500 &
  att=$!
  PYTHONPATH="$types" "$python" "$src/examples/publishers/esc_telemetry_publisher.py" --motors 4 \
    --rate-hz 200 --count 600 &
  esc=$!
  sleep 1.5
  fresh python
  wait "$att" || fail "the Python attitude publisher failed"
  wait "$esc" || fail "the Python ESC publisher failed"

  # Signed: a mixer that requires signatures takes the Python publishers'
  # messages when they are given the bus key (--key), and refuses them
  # without it (counted on the monitor's `signed` line).
  kill -TERM "$mixer"
  wait "$mixer" || fail "motormix run did not exit cleanly"
  "$motormix" keygen "$work/bus.key" > /dev/null
  config+=(--set security.mode=require --set "security.key_file=$work/bus.key")
  "$motormix" run "${config[@]}" --max-cycles 12000 2> "$work/run_signed.log" &
  mixer=$!
  sleep 0.5
  signed_path="$types:$src/python"
  PYTHONPATH="$signed_path" "$python" "$src/examples/publishers/attitude_publisher.py" \
    --rate-hz 500 --count 1500 --key "$work/bus.key" --link-id 3 &
  att=$!
  PYTHONPATH="$signed_path" "$python" "$src/examples/publishers/esc_telemetry_publisher.py" \
    --motors 4 --rate-hz 200 --count 600 --key "$work/bus.key" --link-id 4 &
  esc=$!
  sleep 1.5
  fresh signed
  wait "$att" || fail "the signing Python attitude publisher failed"
  wait "$esc" || fail "the signing Python ESC publisher failed"
  grep -Eq '^signed +require +verified [1-9][0-9]* .*refused: unsigned 0 +bad signature 0' \
    "$work/signed.monitor.txt" || fail "signed: $(grep '^signed' "$work/signed.monitor.txt")"
else
  echo "check_publisher_examples: no LCM Python bindings: the Python publishers were not run"
  status=77
fi
kill -TERM "$mixer"
wait "$mixer" || fail "motormix run did not exit cleanly"
trap - EXIT
[ "$status" = 0 ] && echo "check_publisher_examples: all checks passed"
exit "$status"
