#!/usr/bin/env bash
# Runs one libFuzzer target, bounded: first every committed regression input
# and seed once, then fuzzing for SECONDS into a scratch corpus. Prints the
# executions and coverage reached (scripts/robustness collects them).
#   run_fuzzer.sh BINARY SECONDS MAX_LEN WORK_DIR SEED_DIR...
set -euo pipefail
bin="$(realpath "$1")" seconds="$2" max_len="$3" work="$4"
shift 4
name=$(basename "$bin")
mkdir -p "$work/corpus"
inputs=()
for d in "$@"; do [ -d "$d" ] && inputs+=("$(realpath "$d")"); done
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export TMPDIR="$work"
cd "$work"
# Regressions and seeds, once each.
"$bin" -runs=0 -max_len="$max_len" "${inputs[@]}" > replay.log 2>&1 \
  || { tail -40 replay.log; echo "$name: a regression input or seed fails" >&2; exit 1; }
# Then fuzz, bounded in time; -timeout turns a hang into a failure.
"$bin" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 -artifact_prefix="$work/" corpus "${inputs[@]}" > fuzz.log 2>&1 \
  || { tail -60 fuzz.log; echo "$name: crash, leak, hang or invariant violation (input saved in $work)" >&2; exit 1; }
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' fuzz.log | tail -1)
cov=$(grep -oE 'cov: [0-9]+' fuzz.log | tail -1 | awk '{print $2}')
ft=$(grep -oE 'ft: [0-9]+' fuzz.log | tail -1 | awk '{print $2}')
echo "$name: ${execs:-?} executions in ${seconds} s, coverage ${cov:-?} edges, ${ft:-?} features, corpus $(ls corpus | wc -l) inputs; no crash"
