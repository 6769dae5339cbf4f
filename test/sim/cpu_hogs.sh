# Sourced by the lockstep tests: a busy loop on every core, each bounded by
# `timeout`, stopped on exit. Lockstep must not care how loaded the machine
# is; these tests load it to the full to show that.
#   . cpu_hogs.sh; start_hogs SECONDS   (stop_hogs runs at exit)
hogs=""
stop_hogs() {
  for h in $hogs; do kill "$h" 2>/dev/null || true; done
  hogs=""
}
start_hogs() {
  i=0
  while [ "$i" -lt "$(nproc)" ]; do
    timeout "$1" sh -c 'while :; do :; done' &
    hogs="$hogs $!"
    i=$((i + 1))
  done
}
