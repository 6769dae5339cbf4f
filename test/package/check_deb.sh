#!/usr/bin/env bash
# Builds the .deb with CPack from a motormix build, lists it, checks its
# control fields, extracts it into a scratch root and runs the binary from there.
#   check_deb.sh BUILD_DIR WORK_DIR
set -euo pipefail
build="$1" work="$2"
fail() { echo "check_deb: FAIL: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
command -v dpkg-deb >/dev/null || fail "dpkg-deb missing (Debian's dpkg)"

echo "--- cpack -G DEB"
(cd "$build" && cpack -G DEB -B "$work" > "$work/cpack.log" 2>&1) || { cat "$work/cpack.log"; fail "cpack"; }
deb=$(find "$work" -maxdepth 1 -name 'motormix_*.deb' | head -1)
[ -n "$deb" ] || fail "no motormix_*.deb produced"
echo "$(basename "$deb")"

echo "--- control"
dpkg-deb -f "$deb" Package Version Architecture Depends Recommends | tee "$work/control.txt"
depends=$(dpkg-deb -f "$deb" Depends)
for pkg in liblcm1 libyaml-cpp libstdc++6 libc6; do
  grep -q "$pkg" <<<"$depends" || fail "Depends lacks $pkg: $depends"
done
version=$(dpkg-deb -f "$deb" Version)

echo "--- contents"
dpkg-deb -c "$deb" | awk '{print $NF}' | sed 's|^\./|/|' > "$work/contents.txt"
wc -l < "$work/contents.txt"
for f in /usr/bin/motormix /usr/include/motormix/mixer.hpp /usr/include/motormix/motor_pwm_t.hpp \
    /usr/include/motormix/embedded_mixer.hpp /usr/lib/cmake/motormix/motormixConfig.cmake \
    /usr/lib/pkgconfig/motormix.pc /usr/lib/python3/dist-packages/motormix/motor_pwm_t.py \
    /usr/share/motormix/lcmtypes/motor_pwm_t.lcm /usr/share/motormix/config/quad_x.yaml \
    /usr/share/doc/motormix/README.md; do
  grep -qx "$f" "$work/contents.txt" || fail "the .deb lacks $f"
done
grep -q '^/usr/lib/libmotormix_core' "$work/contents.txt" || fail "the .deb lacks libmotormix_core"

echo "--- extracted into a scratch root"
dpkg-deb -x "$deb" "$work/root"
"$work/root/usr/bin/motormix" --version | tee "$work/version.txt"
grep -qx "motormix $version" "$work/version.txt" || fail "--version does not say $version"
"$work/root/usr/bin/motormix" run --check --config "$work/root/usr/share/motormix/config/hexa_x.yaml" >/dev/null \
  || fail "the packaged binary refuses the packaged hexa_x.yaml"
echo "check_deb: all checks passed"
