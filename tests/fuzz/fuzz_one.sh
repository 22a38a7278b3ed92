#!/usr/bin/env bash
# Runs one libFuzzer target of `make fuzz` (see the Makefile): fuzz_one.sh BUILD_DIR SECONDS TARGET.
# Starts from the committed seeds (tests/fuzz/corpus/TARGET) and the build's own corpus, writes
# new inputs to BUILD_DIR/corpus/TARGET and crashes to BUILD_DIR/crashes; prints one line of
# statistics, or the log's tail and exits 1 on a finding.
set -u
build="$1" seconds="$2" target="$3"
log="$build/$target.log"
mkdir -p "$build/corpus/$target" "$build/crashes"
if ! "$build/tests/fuzz/$target" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=4096 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$build/crashes/$target-" \
    "$build/corpus/$target" "tests/fuzz/corpus/$target" 2>"$log"; then
  echo "fuzzing $target for $seconds s: FOUND A FAILURE ($log)"
  tail -40 "$log"
  exit 1
fi
echo "fuzzing $target for $seconds s: $(grep -E "stat::number_of_executed_units|stat::new_units_added" "$log" | tr -s ' ' | tr '\n' ' ')"
