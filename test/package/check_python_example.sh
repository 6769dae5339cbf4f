#!/usr/bin/env bash
# Runs examples/python/mixer_client.py, with the Python message types of an
# installed motormix, against a running `motormix run` on a private bus.
#   scripts/private-bus check_python_example.sh BUILD_DIR SOURCE_DIR WORK_DIR PYTHON
set -euo pipefail
if [ "${MOTORMIX_PRIVATE_BUS:-}" != "1" ]; then echo "run through scripts/private-bus" >&2; exit 2; fi
build="$1" src="$2" work="$3" python="$4"
fail() { echo "check_python_example: FAIL: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
prefix="$work/prefix"

# Bounded: the mixer stops by itself after 20 s at 400 Hz if nothing else stops it.
"$prefix/bin/motormix" run --config "$prefix/share/motormix/config/quad_x.yaml" --max-cycles 8000 \
  2> "$work/mixer.log" &
mixer=$!
trap 'kill "$mixer" 2>/dev/null || true' EXIT

PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" "$src/examples/python/mixer_client.py" \
  --throttle 0.5 --roll 0.2 --count 5 --timeout 10 | tee "$work/client.txt" \
  || { cat "$work/mixer.log"; fail "the client got no armed outputs"; }
[ "$(grep -c '^armed ' "$work/client.txt")" = 5 ] || fail "expected 5 armed output lines"
# quad_x.yaml: 1000..2000 us; roll 0.2 lowers the right motors (m1, m4) below the left (m2, m3).
"$python" - "$work/client.txt" <<'PY'
import sys
for line in open(sys.argv[1]):
    f = line.split()
    pwm = [float(f[i]) for i in range(2, len(f), 2)]
    assert len(pwm) == 4 and all(1000.0 <= p <= 2000.0 for p in pwm), line
    assert pwm[1] > pwm[0] and pwm[2] > pwm[3], f"roll right should favour the left motors: {line}"
print("outputs in range, roll in the right direction")
PY
kill -TERM "$mixer"
wait "$mixer" || fail "motormix did not exit cleanly"
trap - EXIT
echo "check_python_example: all checks passed"
