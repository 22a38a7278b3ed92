#!/usr/bin/env bash
# examples/cpp/mapping_beside_planning as a user runs it: a TUM folder rendered by the nbv
# command (48 views of the bunny), replayed at its timestamps' pace while the planner decides
# after each frame; then a folder that is not one, refused naming the missing file.
# Usage: example_cpp_test.sh NBV_BINARY EXAMPLE_BINARY
set -euo pipefail
NBV="$1"
EXAMPLE="$2"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
"$NBV" render --model bunny --tum-out seq >render.txt 2>&1 || { cat render.txt; echo "FAIL: nbv render --tum-out"; exit 1; }
"$EXAMPLE" seq >out.txt 2>err.txt || { cat out.txt err.txt; echo "FAIL: the example exited non-zero"; exit 1; }
cat out.txt
grep -q "^48 depth frames" out.txt || { echo "FAIL: the example did not read 48 frames"; exit 1; }
grep -q "after frame  48/48" out.txt || { echo "FAIL: no decision after the last frame"; exit 1; }
occupied=$(sed -n 's/.* \([0-9]*\) occupied.*/\1/p' out.txt)
[ "${occupied:-0}" -gt 1000 ] || { echo "FAIL: the map holds ${occupied:-no} occupied voxels"; exit 1; }
mkdir notum
if "$EXAMPLE" notum >out.txt 2>err.txt; then echo "FAIL: a folder without depth.txt was accepted"; exit 1; fi
grep -q "notum/" err.txt || { cat err.txt; echo "FAIL: the error does not name the missing list"; exit 1; }
echo "example: mapping_beside_planning decided after every frame of a rendered sequence"
