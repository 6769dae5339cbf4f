#!/usr/bin/env bash
# Checks the jar of the message types: one class per .lcm type, each an LCM
# encodable with a fingerprint, loadable next to LCM's own lcm.jar; then the
# way lcm-spy uses it: a flight replayed by motormix (C++ encoder) is read back
# in Java and every event on the motormix channels decodes with its class,
# and so does every event of the same log signed.
#   check_java.sh JAR LCM_JAR MOTORMIX CONFIG FLIGHT WORKDIR PWM_MIN PWM_MAX \
#                 CHANNEL=TYPE... -- TYPE...
set -euo pipefail
jar_file="$1" lcm_jar="$2" motormix="$3" config="$4" flight="$5" work="$6" pwm_min="$7" pwm_max="$8"
shift 8
channels=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do channels+=("$1"); shift; done
[ $# -gt 0 ] && shift
fail() { echo "check_java: FAIL: $*" >&2; exit 1; }
# JAVA, JAVAC: the JDK the jar was built with (ctest passes them).
java="${JAVA:-java}" javac="${JAVAC:-javac}"
javap="$(dirname "$(command -v "$javac")")/javap"
[ -f "$jar_file" ] || fail "no jar at $jar_file"
listing=$(unzip -Z1 "$jar_file" 2>/dev/null || "$(dirname "$javap")/jar" tf "$jar_file")
for type in "$@"; do
  grep -qx "motormix/$type.class" <<<"$listing" || fail "motormix/$type.class is not in the jar"
  sig=$("$javap" -cp "$jar_file:$lcm_jar" "motormix.$type") || fail "javap cannot load motormix.$type"
  grep -q "implements lcm.lcm.LCMEncodable" <<<"$sig" || fail "motormix.$type is not an LCMEncodable"
  grep -q "LCM_FINGERPRINT" <<<"$sig" || fail "motormix.$type has no LCM_FINGERPRINT"
  echo "motormix.$type ok"
done

rm -rf "$work" && mkdir -p "$work"
# No spool-up ramp: the check below is that every armed output is in range.
"$motormix" replay --config "$config" --set output.spool_up_s=0 "$flight" "$work/replay.lcmlog" > "$work/replay.txt" ||
  fail "motormix replay failed (see $work/replay.txt)"
"$javac" -cp "$jar_file:$lcm_jar" -d "$work" "$(dirname "$0")/java/DecodeLog.java" ||
  fail "DecodeLog.java does not compile against the jar"
"$java" -cp "$jar_file:$lcm_jar:$work" DecodeLog "$work/replay.lcmlog" "$pwm_min" "$pwm_max" \
  "${channels[@]}" || fail "the replayed log does not decode with the jar's classes"
# Signed (motormix sign-log): the signature trailer after each message is
# never read by the classes, so the same log signed decodes the same.
"$motormix" keygen "$work/bus.key" > /dev/null || fail "motormix keygen failed"
"$motormix" sign-log --config "$config" --set "security.key_file=$work/bus.key" \
  "$work/replay.lcmlog" "$work/signed.lcmlog" > /dev/null || fail "motormix sign-log failed"
"$java" -cp "$jar_file:$lcm_jar:$work" DecodeLog "$work/signed.lcmlog" "$pwm_min" "$pwm_max" \
  "${channels[@]}" || fail "the signed log does not decode with the jar's classes"
echo "check_java: all checks passed"
