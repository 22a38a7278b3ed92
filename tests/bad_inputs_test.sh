#!/usr/bin/env bash
# Every file of the bad-input corpus (tests/bad_inputs/MANIFEST), given to the nbv command that
# reads its kind: the command exits non-zero below 128 with exactly one line on stderr naming the
# file (and the expected problem), leaves no output file behind and changes no existing file.
set -u
NBV="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
CORPUS="$(cd "$(dirname "$0")/bad_inputs" && pwd)"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
failures=0
checked=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# refused NAME FILE FRAGMENT -- command...: non-zero < 128, one stderr line naming FILE and FRAGMENT.
refused() {
  local name="$1" file="$2" fragment="$3"; shift 4
  timeout 60 "$@" >out.txt 2>err.txt
  local rc=$?
  checked=$((checked + 1))
  if [ "$rc" -eq 0 ] || [ "$rc" -ge 124 ]; then fail "$name: exit code $rc"; return; fi
  [ "$(wc -l <err.txt)" -eq 1 ] || fail "$name: expected one error line, got: $(head -c 400 err.txt)"
  grep -qF -- "$file" err.txt || fail "$name: error does not name $file: $(cat err.txt)"
  grep -qF -- "$fragment" err.txt || fail "$name: error does not say '$fragment': $(cat err.txt)"
}

# A good scan, map and view file to pair with each bad input.
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0.3 0 0\n0.3 0.1 0.05\n0 0.2 0.1\n' > scan.ply
"$NBV" integrate --map good.vdb --cloud scan.ply --origin 0 0 0.05 --resolution 0.05 >/dev/null || fail "cannot make good.vdb"
printf '1\n1 0 0.5 0 0 0 1\n' > good_views.txt

while IFS=$'\t' read -r kind rel fragment; do
  case "$kind" in ''|'#'*) continue ;; esac
  file="$CORPUS/$rel"
  # The bytes of an existing input before the command (a missing one stays missing).
  before=""; [ -f "$file" ] && before=$(sha256sum <"$file")
  case "$kind" in
    mesh)
      refused "render $rel" "$file" "$fragment" -- "$NBV" render --model "$file" --view-index 0 --out cloud.ply
      [ -e cloud.ply ] && fail "render $rel left cloud.ply"
      ;;
    cloud|cloud_points)
      cp good.vdb map.vdb
      refused "integrate $rel" "$file" "$fragment" -- "$NBV" integrate --map map.vdb --cloud "$file" --origin 0 0 0.05
      cmp -s map.vdb good.vdb || fail "integrate $rel changed the map"
      ;;
    views)
      echo keep > out.csv
      refused "evaluate $rel" "$file" "$fragment" -- "$NBV" evaluate --map good.vdb --views "$file" --csv out.csv
      [ "$(cat out.csv)" = keep ] || fail "evaluate $rel changed out.csv"
      ;;
    map)
      refused "info $rel" "$file" "$fragment" -- "$NBV" info "$file"
      refused "convert $rel" "$file" "$fragment" -- "$NBV" convert "$file" out.ot
      [ -e out.ot ] && fail "convert $rel left out.ot"
      if [ -e "$file" ]; then  # a missing map is created by integrate, as documented
        refused "integrate into $rel" "$file" "$fragment" -- "$NBV" integrate --map "$file" --cloud scan.ply --origin 0 0 0.05
      fi
      refused "evaluate $rel" "$file" "$fragment" -- "$NBV" evaluate --map "$file" --views good_views.txt --csv out.csv
      ;;
    depth|depth_frame)
      cp good.vdb map.vdb
      refused "integrate --depth $rel" "$file" "$fragment" -- "$NBV" integrate --map map.vdb --depth "$file" --pose 0.6 0 0.15 0 0 0 1
      cmp -s map.vdb good.vdb || fail "integrate --depth $rel changed the map"
      ;;
    tum)
      cp good.vdb map.vdb
      refused "integrate --tum $rel" "$file" "$fragment" -- "$NBV" integrate --map map.vdb --tum "$file"
      cmp -s map.vdb good.vdb || fail "integrate --tum $rel changed the map"
      ;;
    frames)
      cp good.vdb map.vdb
      refused "integrate --frames $rel" "$file" "$fragment" -- "$NBV" integrate --map map.vdb --frames "$file" --poses "$file/poses.txt"
      cmp -s map.vdb good.vdb || fail "integrate --frames $rel changed the map"
      ;;
    *) fail "unknown kind '$kind' in MANIFEST" ;;
  esac
  after=""; [ -f "$file" ] && after=$(sha256sum <"$file")
  [ "$before" = "$after" ] || fail "$rel was changed by a failed command"
  [ -z "$(ls -A | grep -v -x -e scan.ply -e good.vdb -e good_views.txt -e map.vdb -e out.csv -e out.txt -e err.txt)" ] ||
    fail "$rel left files behind: $(ls -A)"
done <"$CORPUS/MANIFEST"

echo "$checked refusals checked over the corpus, $failures failures"
[ "$failures" -eq 0 ]
