#!/bin/sh
# clang_build.sh - the second compiler's check, run from tests/ by
# check_stress.c (or by hand: cd tests && sh clang_build.sh).
#
# Every committed solver and driver (generated/*.c), and solvers of the
# generator's other forms (--batch W of both families, --real float,
# --wide-step, the stage loop), must pass clang's front end warning-free
# at -std=c99 -Wall -Wextra -pedantic -Werror, as they pass gcc's in the
# build. clang warns where gcc does not (it found
# -Wbitwise-conditional-parentheses in NAME_itol, 2026-11-26).
# Exit status: 0 pass, 1 fail, 77 when clang is not installed
# (scripts/deps.sh clang).
set -u
CC=${CLANG:-clang}
GEN=${HBVMGEN:-../gen/hbvmgen}
if ! command -v "$CC" >/dev/null 2>&1; then
  echo "clang_build.sh: $CC not found; skipped (install: scripts/deps.sh clang)"
  exit 77
fi
FLAGS="-std=c99 -Wall -Wextra -pedantic -Werror -fsyntax-only"
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM
fail=0
n=0

# Check $1 (a .c with its .h beside it); report failures.
check() {
  # shellcheck disable=SC2086
  if ! "$CC" $FLAGS -I"$(dirname "$1")" -I../runtime "$1" 2>"$tmp/log"; then
    echo "clang_build.sh: $1 is not clean under clang:"
    cat "$tmp/log"
    fail=1
  fi
  n=$((n + 1))
}

for src in ../generated/*.c; do check "$src"; done
# the other forms: model, then hbvmgen's options
while read -r model opts; do
  name=v$n
  # shellcheck disable=SC2086
  if ! "$GEN" $opts -n "$name" -o "$tmp" "../models/$model.ham" 2>"$tmp/log"; then
    echo "clang_build.sh: hbvmgen $opts failed on $model.ham:"
    cat "$tmp/log"
    fail=1
    continue
  fi
  check "$tmp/$name.c"
done <<EOT
pendulum --batch 4 -s 3
chain8 --batch 4 --multiplier const -s 2
kepler --batch 8 -k 16 -s 2
satellites --real float -s 3
pendulum --real float --batch 4 -s 2
satellites --wide-step -s 3
kepler --stage-loop 10 -s 3
EOT
echo "clang_build.sh: $n sources checked under $CC -std=c99 -Wall -Wextra -pedantic -Werror"
exit $fail
