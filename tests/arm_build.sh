#!/bin/sh
# arm_build.sh - the embedded build check of docs/api.md ("The float variant"), run from tests/
# by check_stress.c (or by hand: cd tests && sh arm_build.sh).
#
# Every committed solver (generated/*_k*s*.c, not the drivers *_main.c) must
# compile for a Cortex-M4 with a single-precision FPU, freestanding and
# warning-free, and its undefined symbols must be <math.h> functions or the
# compiler's run-time helpers (__aeabi_*): no malloc, memcpy, printf, ...
# Models generated with --real float (rescaled, constrained, M(q)) must call no
# double-precision math function (sqrtf, not sqrt), and models generated with
# --wide-step (long double, which is double on this target) must compile too.
# Exit status: 0 pass, 1 fail, 77 when arm-none-eabi-gcc is not installed
# (scripts/deps.sh embedded).
set -u
CC=${ARM_CC:-arm-none-eabi-gcc}
NM=${ARM_NM:-arm-none-eabi-nm}
GEN=${HBVMGEN:-../gen/hbvmgen}
if ! command -v "$CC" >/dev/null 2>&1 || ! command -v "$NM" >/dev/null 2>&1; then
  echo "arm_build.sh: $CC not found; skipped (install: scripts/deps.sh embedded)"
  exit 77
fi
FLAGS="-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -ffreestanding -std=c99 -Wall -Wextra -pedantic -Werror -O2"
MATH="sin cos tan asin acos atan atan2 sinh cosh tanh exp log sqrt cbrt pow fabs fmax fmin floor ceil fmod hypot copysign"
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM
fail=0

# Print the undefined symbols of object $1 that are not allowed. $2: the
# allowed <math.h> names, space-separated.
forbidden() {
  "$NM" -u "$1" | awk -v allowed=" $2 " '
    { sym = $NF }
    sym ~ /^__aeabi_/ { next }
    index(allowed, " " sym " ") == 0 { print sym }'
}

# Compile $1 (a .c with its .h beside it) into $tmp; report failures.
compile() {
  obj="$tmp/$(basename "$1" .c).o"
  # shellcheck disable=SC2086
  if ! "$CC" $FLAGS -I"$(dirname "$1")" -c -o "$obj" "$1" 2>"$tmp/log"; then
    echo "arm_build.sh: $1 does not compile for the Cortex-M4:"
    cat "$tmp/log"
    fail=1
    return 1
  fi
}

n=0
for src in ../generated/*_k*s*.c; do
  case "$src" in *_main.c) continue ;; esac
  compile "$src" || continue
  bad=$(forbidden "$obj" "$MATH")
  if [ -n "$bad" ]; then
    echo "arm_build.sh: $src needs symbols beyond <math.h>:" $bad
    fail=1
  fi
  n=$((n + 1))
done
echo "arm_build.sh: $n committed solvers compiled for cortex-m4 (fpv4-sp-d16, -ffreestanding -Werror)"

# Single precision: the float names only, and no double arithmetic (the
# __aeabi_d* helpers emulate it in software on this FPU), not even the
# conversions __aeabi_f2d, __aeabi_d2f: the interface is in float too (h,
# q0, p0, NAME_energy, NAME_constraints, NAME_hidden, NAME_project, the
# statistics).
FMATH=$(for f in $MATH; do printf '%sf ' "$f"; done)
for model in kepler pendulum_angle satellites double_pendulum_angles stiff_bob; do
  mkdir -p "$tmp/$model"
  if ! "$GEN" --real float -s 2 -n "${model}_f" -o "$tmp/$model" "../models/$model.ham" 2>"$tmp/log"; then
    echo "arm_build.sh: hbvmgen --real float failed on $model.ham:"
    cat "$tmp/log"
    fail=1
    continue
  fi
  compile "$tmp/$model/${model}_f.c" || continue
  bad=$(forbidden "$obj" "$FMATH")
  dbl=$("$NM" -u "$obj" | awk '$NF ~ /^__aeabi_(d|[il]2d|ui2d|ul2d|f2d)/ { print $NF }')
  if [ -n "$bad$dbl" ]; then
    echo "arm_build.sh: --real float $model.ham needs double-precision or other symbols:" $bad $dbl
    fail=1
  else
    echo "arm_build.sh: --real float $model.ham: only single-precision math (" $("$NM" -u "$obj" | awk '{print $NF}') ")"
  fi
done

# --wide-step: long double arithmetic and the long-double math names.
LMATH=$(for f in $MATH; do printf '%s %sl ' "$f" "$f"; done)
for model in kepler satellites; do
  mkdir -p "$tmp/w$model"
  if ! "$GEN" --wide-step -s 2 -n "${model}_w" -o "$tmp/w$model" "../models/$model.ham" 2>"$tmp/log"; then
    echo "arm_build.sh: hbvmgen --wide-step failed on $model.ham:"
    cat "$tmp/log"
    fail=1
    continue
  fi
  compile "$tmp/w$model/${model}_w.c" || continue
  bad=$(forbidden "$obj" "$LMATH")
  if [ -n "$bad" ]; then
    echo "arm_build.sh: --wide-step $model.ham needs symbols beyond <math.h>:" $bad
    fail=1
  else
    echo "arm_build.sh: --wide-step $model.ham: compiled (" $("$NM" -u "$obj" | awk '$NF !~ /^__aeabi_/ {print $NF}') ")"
  fi
done
exit $fail
