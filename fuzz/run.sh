#!/usr/bin/env bash
# Runs both fuzzers for a bounded number of inputs, seeded with the test
# scenes: fuzz/run.sh BUILD_DIR [RUNS]. New inputs libFuzzer finds go to
# BUILD_DIR/corpus/<fuzzer>; a crash leaves its input in BUILD_DIR and
# fails the run.
set -euo pipefail
build=$1
runs=${2:-20000}
root=$(cd "$(dirname "$0")/.." && pwd)
seeds=("$root/tests/scenes/import")
[ -d "$root/../shared/scenes" ] && seeds+=("$root/../shared/scenes")
for fuzzer in mitsuba pbrt; do
  corpus="$build/corpus/$fuzzer"
  mkdir -p "$corpus"
  echo "fuzz_$fuzzer: $runs runs"
  start=$SECONDS
  "$build/fuzz_$fuzzer" -runs="$runs" -max_len=16384 -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$build/crash-$fuzzer-" "$corpus" "${seeds[@]}" \
    2> "$build/fuzz_$fuzzer.log" || { tail -40 "$build/fuzz_$fuzzer.log"; exit 1; }
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/fuzz_$fuzzer.log" | tr '\n' ' '
  echo "($((SECONDS - start)) s)"
done
