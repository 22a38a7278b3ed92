#!/usr/bin/env bash
# Sweeps that lose nothing (issue 40), as a user runs them: a sweep stopped by Ctrl-C and one
# killed outright resume to the bytes of an uninterrupted run; shards merge only when they are
# the whole sweep, each once; a merge refuses the options it would ignore.
#   sweep_test.sh NBV_BINARY
set -uo pipefail
NBV="$1"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
expect_error() {  # name, fragment of the one error line, --, command
  local name="$1" fragment="$2"; shift 3
  "$@" >out.txt 2>err.txt
  local rc=$?
  { [ "$rc" -ne 0 ] && [ "$rc" -lt 128 ]; } || fail "$name: exit code $rc"
  grep -qF -- "$fragment" err.txt || fail "$name: the error does not say '$fragment': $(cat err.txt)"
}
same() {  # the files of an experiment that must not depend on how it was run
  for f in results.csv table.md bunny.html; do cmp -s "$1/$f" "$2/$f" || fail "$3: $f differs from the uninterrupted run's"; done
}
# Waits until folder $1 keeps at least $2 runs (at most 60 s).
wait_for_runs() {
  for _ in $(seq 600); do
    [ "$(ls "$1/runs" 2>/dev/null | grep -c '\.json$')" -ge "$2" ] && return 0
    sleep 0.1
  done
  return 1
}
SWEEP=(--models bunny --metrics pc,oa --trials 4 --iterations 3 --no-timings --threads 1)

"$NBV" experiment "${SWEEP[@]}" --out whole >/dev/null 2>&1 || fail "the uninterrupted sweep"
[ "$(ls whole/runs | wc -l)" = 8 ] || fail "whole/runs holds $(ls whole/runs | wc -l) runs, not 8"

# Ctrl-C: the run in flight ends and is kept, the command says how to resume and exits 130.
"$NBV" experiment "${SWEEP[@]}" --out stopped >out.txt 2>err.txt &
pid=$!
wait_for_runs stopped 2 || fail "no run was kept within 60 s"
kill -INT $pid
wait $pid
rc=$?
[ $rc = 130 ] || fail "Ctrl-C: exit code $rc, not 130"
grep -q "runs kept in stopped; \`nbv experiment --resume --out stopped\` runs the [0-9]* left" err.txt ||
  fail "Ctrl-C says nothing of how to resume: $(cat err.txt)"
kept=$(ls stopped/runs | grep -c '\.json$')
[ "$kept" -ge 2 ] && [ "$kept" -lt 8 ] || fail "Ctrl-C kept $kept runs"
[ ! -e stopped/results.csv ] || fail "an interrupted sweep wrote results.csv"
expect_error "run again without --resume" "holds this sweep already, $kept of its 8 runs kept: \`--resume\` finishes it" -- \
  "$NBV" experiment "${SWEEP[@]}" --out stopped
"$NBV" experiment --resume --out stopped >out.txt 2>err.txt || fail "--resume: $(cat err.txt)"
grep -q "$kept kept, $((8 - kept)) to run" out.txt || fail "--resume does not run only what is missing: $(cat out.txt)"
same whole stopped "Ctrl-C and --resume"

# SIGKILL (a node lost, a time limit past its grace): at most the run in flight is lost.
"$NBV" experiment "${SWEEP[@]}" --out killed >/dev/null 2>&1 &
pid=$!
wait_for_runs killed 3 || fail "no run was kept within 60 s"
kill -KILL $pid
wait $pid 2>/dev/null
"$NBV" experiment "${SWEEP[@]}" --resume --out killed >/dev/null 2>err.txt || fail "--resume after SIGKILL: $(cat err.txt)"
same whole killed "SIGKILL and --resume"
[ -z "$(ls -A killed/runs | grep -v '^[0-9]*\.json$')" ] || fail "a cut-short run file was left: $(ls -A killed/runs)"
expect_error "resume another sweep" "holds another sweep, which only it resumes: seeds" -- \
  "$NBV" experiment --models bunny --metrics pc,oa --trials 5 --iterations 3 --no-timings --resume --out killed
expect_error "resume with another option" "holds another sweep, which only it resumes: gamma (0.5 against 0.0)" -- \
  "$NBV" experiment "${SWEEP[@]}" --gamma 0.5 --resume --out killed
# A sweep.json written before an option was added (max_seconds) resumes with its default.
python3 - killed/sweep.json <<'PY' || fail "cannot rewrite sweep.json"
import json, sys
sweep = json.load(open(sys.argv[1]))
del sweep["max_seconds"]
json.dump(sweep, open(sys.argv[1], "w"))
PY
"$NBV" experiment --resume --out killed >out.txt 2>err.txt || fail "--resume of a sweep.json without max_seconds: $(cat err.txt)"
grep -q "8 kept, 0 to run" out.txt || fail "--resume of an older sweep.json: $(cat out.txt)"

# Shards: merged whole they are the unsharded run, pages included.
for k in 1 2 3; do "$NBV" experiment "${SWEEP[@]}" --shard $k/3 --out shard$k >/dev/null 2>&1 || fail "shard $k/3"; done
"$NBV" experiment --merge shard1 shard2 shard3 --out merged >/dev/null 2>err.txt || fail "--merge: $(cat err.txt)"
same whole merged "the merge of three shards"
expect_error "a missing shard" "shard 2/3 (3 runs) is not among the folders" -- \
  "$NBV" experiment --merge shard1 shard3 --out m1
expect_error "a repeated shard" "shard3: is shard 3/3 again" -- "$NBV" experiment --merge shard1 shard2 shard3 shard3 --out m2
"$NBV" experiment --models bunny --metrics pc --trials 4 --iterations 3 --no-timings --shard 2/3 --out foreign >/dev/null 2>&1
expect_error "a foreign shard" "foreign: is a shard of another sweep than shard1: metrics" -- \
  "$NBV" experiment --merge shard1 foreign shard3 --out m3
expect_error "an option a merge ignores" "--models has no effect with --merge" -- \
  "$NBV" experiment --merge shard1 shard2 shard3 --models bunny --out m4
rm shard2/runs/000004.json
expect_error "a shard missing a run" "shard2 (shard 2/3) holds 2 of its 3 runs" -- \
  "$NBV" experiment --merge shard1 shard2 shard3 --out m5
"$NBV" experiment --merge shard1 shard2 shard3 --allow-partial --out partial >/dev/null 2>err.txt || fail "--allow-partial"
grep -q "^Partial: merged with --allow-partial; missing: shard2 (shard 2/3) holds 2 of its 3 runs" partial/table.md ||
  fail "a partial merge's table does not say so: $(tail -2 partial/table.md)"
"$NBV" experiment --resume --out shard2 >/dev/null 2>&1 || fail "--resume of a shard"
"$NBV" experiment --merge shard1 shard2 shard3 --out merged2 >/dev/null 2>&1 || fail "--merge after the shard's resume"
same whole merged2 "the merge after a shard's resume"
for m in m1 m2 m3 m4 m5; do [ ! -e $m ] || fail "a refused merge left $m"; done

if [ "$failures" -eq 0 ]; then echo "sweep: all checks passed"; else echo "sweep: $failures failed"; exit 1; fi
