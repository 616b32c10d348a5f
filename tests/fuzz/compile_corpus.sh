#!/bin/sh
# compile_corpus.sh DIR... - every model in DIR... that gen/hbvmgen accepts
# must emit C that compiles with -std=c99 -Wall -Wextra -pedantic -Werror,
# in double (with its driver) and with --real float. Prints the counts and
# every failure; exit 1 if any. Run from the top of the tree (tests/fuzz/run.sh
# calls it after fuzzing).
set -u
CC=${CC:-cc}
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM
accepted=0 refused=0 bad=0
for dir in "$@"; do
  for model in "$dir"/*; do
    [ -f "$model" ] || continue
    for flags in "--main" "--real float"; do
      rm -rf "$tmp/out"
      # shellcheck disable=SC2086
      if ! timeout 20 gen/hbvmgen $flags -n m -o "$tmp/out" "$model" >/dev/null 2>&1; then
        refused=$((refused + 1))
        continue
      fi
      accepted=$((accepted + 1))
      for c in "$tmp"/out/*.c; do
        if ! $CC -std=c99 -Wall -Wextra -pedantic -Werror -Iruntime -I"$tmp/out" -fsyntax-only "$c" 2>"$tmp/log"; then
          bad=$((bad + 1))
          echo "compile_corpus: $model ($flags): $(basename "$c") does not compile:"
          head -5 "$tmp/log"
          mkdir -p tests/fuzz/artifacts && cp "$model" "tests/fuzz/artifacts/nocompile-$(basename "$model")"
        fi
      done
    done
  done
done
echo "compile_corpus: $accepted generated (double with driver, float), $refused refused, $bad did not compile"
[ "$bad" -eq 0 ]
