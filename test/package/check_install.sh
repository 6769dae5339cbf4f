#!/usr/bin/env bash
# Installs a motormix build into a scratch prefix and uses it the way another
# project would: the install tree's contents, find_package(motormix) from a
# consumer project and from the embedding example (both copied out of the
# source tree first), the same through pkg-config, the Python message modules,
# and the installed binary. Then moves the prefix and builds again: the
# package must be relocatable.
#   check_install.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build="$1" src="$2" work="$3"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
fail() { echo "check_install: FAIL: $*" >&2; exit 1; }
step() { echo "--- $*"; }

step "cmake --install into $prefix"
cmake --install "$build" --prefix "$prefix" > "$work/install.log"

libdir=$(sed -n 's/^libdir=\${prefix}\///p' "$(find "$prefix" -name motormix.pc | head -1)")
[ -n "$libdir" ] || fail "no motormix.pc installed"
for f in bin/motormix \
    include/motormix/mixer.hpp include/motormix/embedded_mixer.hpp include/motormix/version.hpp \
    include/motormix/config/config.hpp include/motormix/motor_pwm_t.hpp \
    include/motormix/setpoint_t.hpp include/motormix/pid_t.hpp include/motormix/mixer_status_t.hpp \
    include/motormix/motor_status_t.hpp include/motormix/battery_t.hpp include/motormix/allocation/motor_failure.hpp \
    include/motormix/output/battery_compensation.hpp include/motormix/allocation/yaw_yielding_allocator.hpp \
    "$libdir/cmake/motormix/motormixConfig.cmake" "$libdir/cmake/motormix/motormixConfigVersion.cmake" \
    "$libdir/cmake/motormix/motormixTargets.cmake" "$libdir/pkgconfig/motormix.pc" \
    lib/python3/dist-packages/motormix/__init__.py lib/python3/dist-packages/motormix/motor_pwm_t.py \
    include/motormix/config/vehicle_physics.hpp include/motormix/vehicle_state_t.hpp \
    share/motormix/scenarios/hover.yaml share/motormix/scenarios/motor_out.yaml \
    share/motormix/lcmtypes/motor_pwm_t.lcm share/motormix/config/quad_x.yaml \
    share/motormix/examples/embedding/embed.cpp share/doc/motormix/README.md \
    share/doc/motormix/CHANGELOG.md share/doc/motormix/docs/running.md; do
  [ -e "$prefix/$f" ] || fail "missing from the install tree: $f"
done
ls "$prefix/$libdir"/libmotormix_core.* "$prefix/$libdir"/libmotormix_config.* >/dev/null \
  || fail "libraries missing from $prefix/$libdir"
# Public headers must stand alone: nothing from the source tree, no yaml-cpp or pugixml.
if grep -rlE 'yaml-cpp|pugixml|"config/|"node/' "$prefix/include/motormix"; then
  fail "installed headers reach into private code or private dependencies (above)"
fi
if grep -rl "$src" "$prefix/$libdir/cmake" "$prefix/$libdir/pkgconfig"; then
  fail "the CMake package or motormix.pc names the source tree (above)"
fi

step "run paths: no empty or relative entry (the loader reads those as the current directory)"
for bin in "$build/motormix" "$prefix/bin/motormix"; do
  paths=$(readelf -d "$bin" | sed -n 's/.*(R\(UN\)\{0,1\}PATH).*\[\(.*\)\]$/\2/p')
  echo "$bin: ${paths:-none}"
  if [ -n "$paths" ]; then
    IFS=: read -r -a entries <<<"$paths:"
    for e in "${entries[@]}"; do
      case "$e" in
        /* | '$ORIGIN'*) ;;
        *) fail "$bin searches libraries in the current directory (run path '$paths')" ;;
      esac
    done
  fi
done

step "installed binary"
"$prefix/bin/motormix" --version | tee "$work/version.txt"
version=$(awk '{print $2}' "$work/version.txt")
grep -q "^Version: $version\$" "$prefix/$libdir/pkgconfig/motormix.pc" \
  || fail "motormix.pc does not carry version $version"
"$prefix/bin/motormix" run --check --config "$prefix/share/motormix/config/quad_x.yaml" > /dev/null
# The simulator from the install tree, on an installed scenario file and on a
# compiled-in one: the hexa flies on after losing a motor.
"$prefix/bin/motormix" sim --config "$prefix/share/motormix/config/hexa_x.yaml" \
  --scenario "$prefix/share/motormix/scenarios/hover.yaml" --fail 2@6 --json > "$work/sim.json" \
  || fail "motormix sim from the install tree failed: $(cat "$work/sim.json")"
grep -q '"crashed":false' "$work/sim.json" || fail "installed motormix sim: $(cat "$work/sim.json")"
"$prefix/bin/motormix" sim --preset octo_x --scenario motor_out --json > /dev/null \
  || fail "installed motormix sim --preset octo_x --scenario motor_out"

consumer_build() {  # NAME SOURCE_DIR PREFIX [EXTRA CMAKE ARGUMENTS...]
  local name="$1" from="$2" pfx="$3"
  shift 3
  rm -rf "$work/$name"
  cp -r "$from" "$work/$name"
  cmake -S "$work/$name" -B "$work/$name/build" -DCMAKE_PREFIX_PATH="$pfx" \
    -DCMAKE_BUILD_TYPE=Release "$@" > "$work/$name.configure.log" \
    || { cat "$work/$name.configure.log"; fail "$name: configure against $pfx"; }
  cmake --build "$work/$name/build" > "$work/$name.build.log" 2>&1 \
    || { cat "$work/$name.build.log"; fail "$name: build against $pfx"; }
}

step "find_package(motormix): motormix::core + motormix::lcmtypes"
consumer_build consumer "$src/test/package/consumer" "$prefix"
"$work/consumer/build/core_and_types"
"$work/consumer/build/signing" | grep -q 'signing: signed' || fail "motormix::signing: not signed"

step "find_package(motormix): the signed controller example (motormix::signing + lcmtypes)"
consumer_build signed_controller "$src/examples/signed_controller" "$prefix"
# Without a key it says so and exits 2 (it flies in the signed_controllers test).
if "$work/signed_controller/build/signed_controller" --key "$work/no-such.key" \
  2> "$work/signed_controller.err"; then
  fail "signed_controller ran without a key"
fi
grep -q "cannot open the key file" "$work/signed_controller.err" ||
  fail "signed_controller: $(cat "$work/signed_controller.err")"

step "find_package(motormix): the README's embedding example (motormix::config)"
consumer_build embedding "$src/examples/embedding" "$prefix"
"$work/embedding/build/embed" "$prefix/share/motormix/config/quad_x.yaml" | tee "$work/embed.txt"
[ "$(grep -c ' command ' "$work/embed.txt")" = 4 ] || fail "embed: expected 4 motor lines"
grep -q 'not delivered: ' "$work/embed.txt" || fail "embed: no saturation report"
if "$work/embedding/build/embed" "$work/no-such.yaml" 2> "$work/embed.err"; then
  fail "embed: a missing config file did not fail"
fi
grep -q 'cannot open' "$work/embed.err" || fail "embed: unclear error for a missing file"

pc_build() {  # PREFIX [EXTRA COMPILER FLAGS...]
  local pc_dir
  pc_dir=$(dirname "$(find "$1" -name motormix.pc | head -1)")
  export PKG_CONFIG_PATH="$pc_dir"
  local flags
  flags=$(pkg-config --cflags --libs motormix) || fail "pkg-config motormix failed under $1"
  local extra=("${@:2}")
  # shellcheck disable=SC2086
  c++ -std=c++17 -O1 "${extra[@]}" "$src/test/package/consumer/core_and_types.cpp" \
    -o "$work/pc_core_and_types" $flags || fail "pkg-config build of the consumer"
  # shellcheck disable=SC2086
  c++ -std=c++17 -O1 "${extra[@]}" "$src/examples/embedding/embed.cpp" -o "$work/pc_embed" $flags \
    || fail "pkg-config build of the embedding example"
  # A prefix outside the linker's path: what a user of pkg-config does for
  # shared libraries (static ones need nothing).
  LD_LIBRARY_PATH="$pc_dir/.." "$work/pc_core_and_types"
  LD_LIBRARY_PATH="$pc_dir/.." "$work/pc_embed" "$1/share/motormix/config/hexa_x.yaml" > /dev/null
}
step "pkg-config motormix"
pc_build "$prefix"

# Eigen lays out the fixed-size objects in motormix's public types for the
# widest SIMD the compiler is told about: a program built with -march=native
# would read them at other offsets than the libraries (built for the baseline)
# wrote them. The package pins the alignment (EIGEN_MAX_ALIGN_BYTES=16) and
# the headers refuse a build without it.
step "a program built for a wider SIMD than the libraries (-march=x86-64-v3)"
wide=-march=x86-64-v3
if [ "$(uname -m)" = x86_64 ] && echo 'int main() {}' | c++ -x c++ "$wide" - -o "$work/wide_probe" 2>/dev/null; then
  # Without the package's flags: refused at compile time, naming the fix
  # (compiling needs no AVX2 in this machine's CPU).
  # shellcheck disable=SC2046
  if c++ -std=c++17 "$wide" -fsyntax-only -I"$prefix/include" $(pkg-config --cflags eigen3) \
      "$src/test/package/consumer/core_and_types.cpp" 2> "$work/wide_refused.log"; then
    fail "motormix's headers compiled with $wide but without the Eigen alignment definition"
  fi
  grep -q 'EIGEN_MAX_ALIGN_BYTES=16' "$work/wide_refused.log" \
    || { cat "$work/wide_refused.log"; fail "the refusal does not name EIGEN_MAX_ALIGN_BYTES=16"; }
  # Through find_package and pkg-config: builds, and where this CPU runs it,
  # answers as the baseline build did.
  consumer_build consumer-wide "$src/test/package/consumer" "$prefix" -DCMAKE_CXX_FLAGS="$wide"
  consumer_build embedding-wide "$src/examples/embedding" "$prefix" -DCMAKE_CXX_FLAGS="$wide"
  pc_build "$prefix" "$wide"
  if grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo; then
    "$work/consumer-wide/build/core_and_types" > "$work/consumer-wide.txt" \
      || fail "the consumer built with $wide failed"
    "$work/consumer/build/core_and_types" | cmp -s - "$work/consumer-wide.txt" \
      || fail "the consumer built with $wide answers differently"
    "$work/embedding-wide/build/embed" "$prefix/share/motormix/config/quad_x.yaml" \
      > "$work/embed-wide.txt" || fail "the embedding example built with $wide failed"
    cmp -s "$work/embed.txt" "$work/embed-wide.txt" \
      || { diff "$work/embed.txt" "$work/embed-wide.txt"; fail "embed built with $wide answers differently"; }
    LD_LIBRARY_PATH="$(dirname "$(find "$prefix" -name motormix.pc | head -1)")/.." \
      "$work/pc_embed" "$prefix/share/motormix/config/quad_x.yaml" | cmp -s - "$work/embed.txt" \
      || fail "the pkg-config build with $wide answers differently"
  else
    echo "this CPU lacks AVX2 or FMA: built with $wide, not run"
  fi
else
  echo "not an x86-64 compiler that takes $wide: skipped"
fi

step "Python message modules (from motormix import motor_pwm_t)"
PYTHONPATH="$prefix/lib/python3/dist-packages" python3 - <<'PY'
from motormix import motor_pwm_t, setpoint_t, pid_t, mixer_status_t, motor_status_t, battery_t
m = motor_pwm_t()
m.utime, m.num_motors, m.command, m.pwm, m.direction, m.armed = 5, 2, [0.5, 1.0], [1500.0, 2000.0], [0, 0], True
back = motor_pwm_t.decode(m.encode())
assert list(back.pwm) == [1500.0, 2000.0] and back.armed, back.pwm
s = motor_status_t()
s.utime, s.num_motors, s.failed = 1, 3, [False, True, False]
assert list(motor_status_t.decode(s.encode()).failed) == [False, True, False]
print("python types ok:", [t.__name__ for t in (motor_pwm_t, setpoint_t, pid_t, mixer_status_t, motor_status_t, battery_t)])
PY

step "relocated prefix"
mv "$prefix" "$work/moved"
consumer_build consumer-moved "$src/test/package/consumer" "$work/moved"
"$work/consumer-moved/build/core_and_types"
pc_build "$work/moved"

echo "check_install: all checks passed"
