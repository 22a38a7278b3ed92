#!/usr/bin/env bash
# The study of docs/RESULTS.md: the 5 original models x every metric x 10 trials (20 scans,
# released rays) under each scene condition, one experiment folder per condition.
# Usage: scripts/study_conditions.sh OUT_DIR [NBV]   (20-40 minutes per condition on 2 cores)
set -euo pipefail
OUT=${1:?usage: study_conditions.sh OUT_DIR [NBV]}
NBV=${2:-build/apps/nbv}
MODELS=bunny,armadillo,dragon,dino,head
mkdir -p "$OUT"
run() {  # run NAME FLAGS...
  local name=$1; shift
  [ -f "$OUT/$name/table.md" ] && { echo "$name: done already"; return; }
  echo "== $name: $*"
  "$NBV" experiment --models $MODELS --metrics all --trials 10 --iterations 20 --rays released "$@" --force \
    --out "$OUT/$name"
}
run bare --scene bare
run ground --scene bare --ground-plane
run released --scene released
run clear --scene bare --no-return clear
run ground-clear --scene bare --ground-plane --no-return clear
run ground-upright --scene bare --ground-plane --up auto
