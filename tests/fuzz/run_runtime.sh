#!/bin/sh
# Build the libFuzzer harness of the driver library's parsers and run it.
#   tests/fuzz/run_runtime.sh [SECONDS]   (default 60; make fuzz FUZZ_SECONDS=...)
# Needs clang with libFuzzer (scripts/deps.sh fuzz). The harness
# (fuzz_runtime.c: the option line and the ensemble CSV, see its comment) is
# built in build/fuzz/ with -fsanitize=fuzzer,address,undefined from
# runtime/*.c; it includes runtime/ensemble.c itself, for its static
# preamble. New interesting inputs go to tests/fuzz/corpus-runtime-run/, the
# seeds are tests/fuzz/corpus-runtime/, and an input that crashes, leaks,
# trips a sanitizer or runs longer than 10 s is written to
# tests/fuzz/artifacts/ as runtime-crash-... (both directories are
# git-ignored). Extra arguments after SECONDS go to the fuzzer (-jobs=2), or
# run one input:  build/fuzz/fuzz_runtime FILE
set -eu
cd "$(dirname "$0")/../.."
secs=${1:-60}
[ $# -gt 0 ] && shift
CLANG=${CLANG:-clang}
B=build/fuzz
mkdir -p "$B" tests/fuzz/corpus-runtime-run tests/fuzz/artifacts

FLAGS="-g -O1 -std=c99 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
# The ensemble's trajectory limit 100 times smaller: --sweep's allocation
# at the limit stays fast under the sanitizers, and the limit is reached.
INC="-Iruntime -DHBVMRT_MAX_TRAJ=100000L"
objs=""
for src in $(ls runtime/*.c | grep -v '^runtime/ensemble\.c$') tests/fuzz/fuzz_runtime.c; do
  obj="$B/rt-$(basename "$src" .c).o"
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ runtime/ensemble.c -nt "$obj" ] ||
     [ -n "$(find runtime -name '*.h' -newer "$obj")" ]; then
    # shellcheck disable=SC2086
    $CLANG $FLAGS -Wall -Wextra $INC -c -o "$obj" "$src"
  fi
  objs="$objs $obj"
done
# shellcheck disable=SC2086
$CLANG $FLAGS -o "$B/fuzz_runtime" $objs -lm

# -close_fd_mask=3: the driver's errors and --help are silenced; the
# fuzzer's and the sanitizers' reports still go to stderr.
"$B/fuzz_runtime" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
  -dict=tests/fuzz/runtime.dict -close_fd_mask=3 -artifact_prefix=tests/fuzz/artifacts/runtime- \
  -print_final_stats=1 "$@" tests/fuzz/corpus-runtime-run tests/fuzz/corpus-runtime
