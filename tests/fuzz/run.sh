#!/bin/sh
# Build the libFuzzer harness of the generator's front end and run it.
#   tests/fuzz/run.sh [SECONDS]     (default 60; make fuzz FUZZ_SECONDS=...)
# Needs clang with libFuzzer (scripts/deps.sh fuzz). The harness is built in
# build/fuzz/ with -fsanitize=fuzzer,address,undefined from gen/*.c (not
# main.c) and the bison/flex outputs. New interesting inputs go to
# tests/fuzz/corpus-run/, the seeds are tests/fuzz/corpus/, and an input that
# crashes, leaks, trips a sanitizer or runs longer than 10 s is written to
# tests/fuzz/artifacts/ (both directories are git-ignored).
# Extra arguments after SECONDS are passed to the fuzzer (e.g. -jobs=2), or
# run one input:  build/fuzz/fuzz_frontend FILE
set -eu
cd "$(dirname "$0")/../.."
secs=${1:-60}
[ $# -gt 0 ] && shift
CLANG=${CLANG:-clang}
B=build/fuzz
mkdir -p "$B" tests/fuzz/corpus-run tests/fuzz/artifacts

make --no-print-directory build/gen/parser.c build/gen/lexer.c >/dev/null

FLAGS="-g -O1 -std=c99 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
# (bison's YYTRANSLATE compares a char with a larger constant: clang warns)
WNO="-Wno-unused-function -Wno-tautological-constant-out-of-range-compare"
# The generator's resource limits scaled down by 10: the paths that enforce
# them are exercised as often, but an instrumented run reaching them stays
# well within the 10 s timeout (natively they take up to ~3 s).
LIMITS="-DMAX_NODES=400000 -DMAX_WORK=2000000L"
INC="-Igen -Ibuild/gen $(pkg-config --cflags gsl) $LIMITS"
objs=""
# every pass of the generator but main.c (the harness stands in for it)
gen_srcs=$(ls gen/*.c | grep -v '^gen/main\.c$')
for src in $gen_srcs build/gen/parser.c build/gen/lexer.c tests/fuzz/fuzz_frontend.c; do
  obj="$B/$(basename "$src" .c).o"
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find gen -name '*.h' -newer "$obj")" ]; then
    # shellcheck disable=SC2086
    $CLANG $FLAGS $WNO $INC -c -o "$obj" "$src"
  fi
  objs="$objs $obj"
done
# shellcheck disable=SC2086
$CLANG $FLAGS -o "$B/fuzz_frontend" $objs \
  -Wl,--wrap=exit,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free \
  $(pkg-config --libs gsl) -lm

# -close_fd_mask=2: the generator's diagnostics are silenced; the fuzzer's
# and the sanitizers' reports still go to stderr.
"$B/fuzz_frontend" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=8192 \
  -dict=tests/fuzz/ham.dict -close_fd_mask=2 -artifact_prefix=tests/fuzz/artifacts/ -print_final_stats=1 \
  "$@" tests/fuzz/corpus-run tests/fuzz/corpus

# Then every model of the corpus that the generator accepts must give C that
# compiles warning-free, in double and in float (the harness emits to
# /dev/null: compiling each input there would slow it a hundredfold).
make --no-print-directory all >/dev/null
tests/fuzz/compile_corpus.sh tests/fuzz/corpus-run tests/fuzz/corpus
