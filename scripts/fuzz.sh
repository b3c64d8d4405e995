#!/usr/bin/env bash
# Runs one libFuzzer harness of tests/fuzz: scripts/fuzz.sh NAME SECONDS [BUILD_DIR (default build-asan)].
# Seeds come from tests/fuzz/corpus/NAME; new inputs go to .cache/fuzz/NAME and crashes to .cache/fuzz/crashes/
# (both ignored). Prints libFuzzer's final stats (stat::number_of_executed_units is the execution count).
set -euo pipefail
name=$1
seconds=$2
root=$(cd "$(dirname "$0")/.." && pwd)
build=${3:-$root/build-asan}
work=$root/.cache/fuzz/$name
mkdir -p "$work" "$root/.cache/fuzz/crashes"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# PRT_FUZZ_SEED and PRT_FUZZ_RUNS make a run repeatable (ctest's smoke sets both: CI must not depend on luck);
# without them a long run draws a new seed.
extra=()
[ -n "${PRT_FUZZ_SEED:-}" ] && extra+=(-seed="$PRT_FUZZ_SEED")
[ -n "${PRT_FUZZ_RUNS:-}" ] && extra+=(-runs="$PRT_FUZZ_RUNS")
exec "$build/tests/fuzz/fuzz_$name" -max_total_time="$seconds" "${extra[@]}" -rss_limit_mb=2048 -timeout=30 -print_final_stats=1 \
  -artifact_prefix="$root/.cache/fuzz/crashes/$name-" "$work" "$root/tests/fuzz/corpus/$name"
