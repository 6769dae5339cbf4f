#!/usr/bin/env bash
# Checks the jar of the message types: one class per .lcm type, each an LCM
# encodable with a fingerprint, loadable next to LCM's own lcm.jar (what
# lcm-spy needs to decode the motormix channels).
#   check_java.sh JAR LCM_JAR TYPE...
set -euo pipefail
jar_file="$1" lcm_jar="$2"
shift 2
fail() { echo "check_java: FAIL: $*" >&2; exit 1; }
[ -f "$jar_file" ] || fail "no jar at $jar_file"
listing=$(unzip -Z1 "$jar_file" 2>/dev/null || jar tf "$jar_file")
for type in "$@"; do
  grep -qx "motormix/$type.class" <<<"$listing" || fail "motormix/$type.class is not in the jar"
  sig=$(javap -cp "$jar_file:$lcm_jar" "motormix.$type") || fail "javap cannot load motormix.$type"
  grep -q "implements lcm.lcm.LCMEncodable" <<<"$sig" || fail "motormix.$type is not an LCMEncodable"
  grep -q "LCM_FINGERPRINT" <<<"$sig" || fail "motormix.$type has no LCM_FINGERPRINT"
  echo "motormix.$type ok"
done
echo "check_java: all checks passed"
