#!/usr/bin/env bash
# The shipped Slurm sweep (scripts/slurm/sweep.sh) on a real one-node cluster (run inside
# scripts/slurm/local_cluster.sh, which sets SLURM_CONF; `make slurm-test` does both):
#   1. a sweep of 3 shards and its merge job give results.csv and table.md byte for byte as
#      one unsharded `nbv experiment`;
#   2. a sweep whose task 2 fails: the merge job never runs, and a merge by hand is refused.
#   slurm_test.sh NBV_BINARY
set -uo pipefail
NBV="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
SWEEP_SH="$(cd "$(dirname "$0")/../scripts/slurm" && pwd)/sweep.sh"
WORK=$(mktemp -d /tmp/nbv-slurm-XXXXXX)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
[ -n "${SLURM_CONF:-}" ] || { echo "FAIL: SLURM_CONF is not set: run me inside scripts/slurm/local_cluster.sh"; exit 1; }
SWEEP=(--models bunny --metrics pc,oa --trials 3 --iterations 3 --no-timings)

start=$(date +%s%N)
"$NBV" experiment "${SWEEP[@]}" --threads 2 --out whole >whole.log 2>&1 || fail "the unsharded sweep: $(tail -3 whole.log)"
one=$(( ($(date +%s%N) - start) / 1000000 ))
start=$(date +%s%N)
NBV="$NBV" bash "$SWEEP_SH" --shards 3 --out sharded --cpus 1 --time 0:10:00 --wait -- "${SWEEP[@]}" >submit.log 2>&1 ||
  fail "the sharded sweep: $(cat submit.log; tail -5 sharded/logs/*.out)"
sharded=$(( ($(date +%s%N) - start) / 1000000 ))
for f in results.csv table.md; do
  cmp -s whole/$f sharded/results/$f || fail "$f of the Slurm sweep differs from one process's"
done
[ -s sharded/results/bunny.html ] && [ -s sharded/results/bunny.png ] || fail "the merge wrote no page or plot: $(ls sharded/results)"
echo "one process (2 threads): $one ms; 3 shards on Slurm (1 CPU each, 2 at a time) and the merge: $sharded ms"

# Task 2 fails (its folder is a file): the merge job is cancelled, never run.
mkdir -p broken/shards && touch broken/shards/2
if NBV="$NBV" bash "$SWEEP_SH" --shards 3 --out broken --cpus 1 --wait -- "${SWEEP[@]}" >submit.log 2>&1; then
  fail "a sweep with a failed task reported success: $(cat submit.log)"
fi
merge=$(sed -n 's/^merge job \([0-9]*\): runs after.*/\1/p' submit.log)
[ -n "$merge" ] || fail "no merge job id: $(cat submit.log)"
state=$(scontrol show job "$merge" 2>/dev/null | grep -o 'JobState=[A-Z_]*' || true)
[ "$state" = JobState=CANCELLED ] || fail "the merge job of a failed sweep: $state, not CANCELLED"
[ ! -e broken/results ] || fail "the merge of a failed sweep wrote broken/results"
grep -q "broken/shards/2: is a file, not a folder" broken/logs/shard-2.out || fail "task 2 failed otherwise: $(cat broken/logs/shard-2.out)"
if "$NBV" experiment --merge broken/shards/1 broken/shards/3 --out by-hand 2>err.txt; then fail "a merge by hand of 2 of 3 shards succeeded"; fi
grep -q "shard 2/3 (2 runs) is not among the folders" err.txt || fail "the merge by hand: $(cat err.txt)"

if [ "$failures" -eq 0 ]; then echo "slurm: all checks passed"; else echo "slurm: $failures failed"; exit 1; fi
