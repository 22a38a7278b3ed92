#!/usr/bin/env bash
# A user's clone holds only the repository: nothing in it may point outside it. Every file git
# tracks is checked for references to the developers' shared folder, every `SEMANTICS.md
# "Section"` citation for a section docs/SEMANTICS.md has, and every relative Markdown link
# for a file that exists.
set -u
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
files=$(git ls-files 2>/dev/null || find . -type f -not -path './build*' -not -path './.git/*' -not -path './data/*')
[ -n "$files" ] || { echo "FAIL: no files to check"; exit 1; }
me=tests/self_contained_test.sh
# 1. Paths and documents outside the repository.
for pattern in '\.\./shared' '\bSPEC\b' 'STYLE\.md' 'shared/reference'; do
  hits=$(grep -nIE "$pattern" $files 2>/dev/null | grep -v "^$me:")
  [ -n "$hits" ] && fail "reference outside the repository ($pattern):
$hits"
done
# 2. Cited sections exist.
sections=$(sed -n 's/^## //p' docs/SEMANTICS.md)
cited=$(grep -ohIE 'SEMANTICS\.md,? "[^"]+"(, "[^"]+")*' $files | grep -oE '"[^"]+"' | tr -d '"' | sort -u)
while IFS= read -r section; do
  [ -z "$section" ] && continue
  grep -qxF -- "$section" <<<"$sections" || fail "SEMANTICS.md has no section \"$section\""
done <<<"$cited"
# 3. Relative Markdown links resolve (anchors to a heading of the target).
for md in $(grep -lE '\]\(' $(grep -E '\.md$' <<<"$files")); do
  dir=$(dirname "$md")
  for link in $(grep -oE '\]\([^)# ]+(#[^) ]+)?\)' "$md" | sed -E 's/^\]\(//; s/\)$//'); do
    case "$link" in http*|mailto:*) continue ;; esac
    target="${link%%#*}"
    anchor=""; [[ "$link" == *#* ]] && anchor="${link#*#}"
    [ -e "$dir/$target" ] || { fail "$md: link to missing $target"; continue; }
    if [ -n "$anchor" ]; then
      sed -n 's/^#\+ //p' "$dir/$target" | tr 'A-Z' 'a-z' | sed -E 's/[^a-z0-9 -]//g; s/ /-/g' | grep -qxF -- "$anchor" ||
        fail "$md: $target has no heading for #$anchor"
    fi
  done
done
if [ "$failures" -eq 0 ]; then echo "self-contained: every reference stays in the repository"; else exit 1; fi
