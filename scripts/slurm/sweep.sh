#!/usr/bin/env bash
# An `nbv experiment` sweep on a Slurm cluster: an array job of N tasks, task K running shard
# K/N into OUT/shards/K (with --resume, so a requeued or re-submitted task finishes its shard
# instead of starting it again), and a merge job that runs only once every task succeeded
# (--dependency=afterok, --kill-on-invalid-dep=yes: a failed task cancels it) and writes the
# whole sweep into OUT/results. The sweep's options are given once, after `--`.
#
#   scripts/slurm/sweep.sh --shards N --out OUT [--cpus C] [--time T] [--partition P] [--wait] \
#       -- --models all --metrics all --trials 20 [any other option of nbv experiment]
#
# NBV names the nbv binary (default: the one on PATH), resolved here so that every task runs the
# same. --cpus: CPUs per task, passed to nbv as --threads (default 1). --time: each task's limit
# (default 1:00:00); a task stopped by it keeps its finished runs, and submitting the same
# command again resumes every shard. --wait: return when the merge job ends: 0 if it completed,
# 1 if it failed or was cancelled (a task failed).
# Prints the array and merge job ids. Logs: OUT/logs/shard-K.out and OUT/logs/merge.out.
set -euo pipefail
usage() {
  echo "usage: $0 --shards N --out OUT [--cpus C] [--time T] [--partition P] [--wait] -- EXPERIMENT_OPTIONS..." >&2
  exit 2
}
shards="" out="" cpus=1 time_limit=1:00:00 partition="" wait=""
while [ $# -gt 0 ]; do
  case $1 in
    --shards) shards=${2:-}; shift 2 ;;
    --out) out=${2:-}; shift 2 ;;
    --cpus) cpus=${2:-}; shift 2 ;;
    --time) time_limit=${2:-}; shift 2 ;;
    --partition) partition=${2:-}; shift 2 ;;
    --wait) wait=--wait; shift ;;
    --) shift; break ;;
    *) echo "$0: unknown option '$1'" >&2; usage ;;
  esac
done
case $shards in '' | *[!0-9]* | 0) echo "$0: --shards '$shards' is not a whole number >= 1" >&2; usage ;; esac
case $cpus in '' | *[!0-9]* | 0) echo "$0: --cpus '$cpus' is not a whole number >= 1" >&2; usage ;; esac
[ -n "$out" ] || { echo "$0: --out names no folder" >&2; usage; }
for option in "$@"; do
  case $option in
    --shard | --shard=* | --out | --out=* | --merge | --merge=* | --threads | --threads=*)
      echo "$0: give $option to this script's options, not to the sweep's: it sets --shard, --out and --threads" >&2
      exit 2 ;;
  esac
done
nbv=$(command -v "${NBV:-nbv}") || { echo "$0: no nbv binary (put it on PATH or name it in NBV)" >&2; exit 2; }
command -v sbatch >/dev/null || { echo "$0: sbatch is missing (apt-get install slurm-client)" >&2; exit 2; }
mkdir -p "$out/shards" "$out/logs"
out=$(cd "$out" && pwd)

# The sweep's options, quoted once for the jobs' shells.
quoted=$(printf ' %q' "$@")

common=(--parsable --job-name=nbv-sweep ${partition:+--partition="$partition"})
array=$(sbatch "${common[@]}" --array="1-$shards" --cpus-per-task="$cpus" --time="$time_limit" \
  --output="$out/logs/shard-%a.out" \
  --wrap="exec $(printf %q "$nbv") experiment$quoted --threads $cpus --shard \$SLURM_ARRAY_TASK_ID/$shards --resume \
--out $(printf %q "$out")/shards/\$SLURM_ARRAY_TASK_ID")
array=${array%%;*}
folders=$(for k in $(seq "$shards"); do printf ' %q' "$out/shards/$k"; done)
echo "array job $array: $shards shards into $out/shards"
merge=$(sbatch "${common[@]}" --dependency="afterok:$array" --kill-on-invalid-dep=yes --cpus-per-task=1 \
  --output="$out/logs/merge.out" \
  --wrap="exec $(printf %q "$nbv") experiment --merge$folders --out $(printf %q "$out")/results --force")
merge=${merge%%;*}
echo "merge job $merge: runs after every shard succeeded, into $out/results"
[ -n "$wait" ] || exit 0
# --wait: until the merge job ends (sbatch --wait polls at up to 32 s), then its state.
while :; do
  state=$(scontrol show job "$merge" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
  case $state in PENDING | RUNNING | CONFIGURING | COMPLETING | REQUEUED | RESIZING | SUSPENDED) sleep 0.5 ;; *) break ;; esac
done
echo "merge job $merge: ${state:-gone from slurmctld}"
[ "$state" = COMPLETED ]
