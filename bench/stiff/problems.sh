# shellcheck shell=sh disable=SC2034
# bench/stiff/problems.sh - sourced by bench/stiff/run.sh and bound.sh: the
# stiff problems' models (written into $B/models) and the h each method's
# line starts from.
# The fastest frequency omega of each problem (h omega in the tables)
STIFF_OMEGA='fpu50=50 fpu1000=1000 stiff_bob=141.42 stiff_bob6=1414.2 butane=175.1'

# The model of a problem, written into $B/models.
model() {
  case $1 in
  fpu50) cp models/fpu.ham "$B/models/$1.ham" ;;
  fpu1000) sed 's/^param omega = 50$/param omega = 1000/' models/fpu.ham >"$B/models/$1.ham" ;;
  stiff_bob) cp models/stiff_bob.ham "$B/models/$1.ham" ;;
  stiff_bob6) sed 's/^param k = 1e4$/param k = 1e6/' models/stiff_bob.ham >"$B/models/$1.ham" ;;
  butane) cp models/butane.ham "$B/models/$1.ham" ;;
  esac
  grep -q "$(omega_param "$1")" "$B/models/$1.ham" || { echo "bench/stiff: $1's parameter not set" >&2; exit 1; }
}
omega_param() {
  case $1 in
  fpu1000) echo "param omega = 1000" ;;
  stiff_bob6) echo "param k = 1e6" ;;
  *) echo "param" ;;
  esac
}

# The largest h of each method's line (T = 10, h halving): Newton from
# h omega of about 1000 (FPU), 40 (bob, butane), 140 (bob at k = 1e6);
# the fixed-point step from h omega of about 4, where it starts to fail.
newton_from() {
  case $1 in
  fpu50) echo 0.5 ;; fpu1000) echo 1 ;; stiff_bob) echo 0.3 ;; stiff_bob6) echo 0.1 ;; butane) echo 0.2 ;;
  esac
}
fixed_from() {
  case $1 in
  fpu50) echo 0.08 ;; fpu1000) echo 0.004 ;; stiff_bob) echo 0.03 ;; stiff_bob6) echo 0.003 ;; butane) echo 0.025 ;;
  esac
}
has_constraints() { case $1 in stiff_bob* | butane) return 0 ;; *) return 1 ;; esac }

# The solvers of problem P at degree S (-k auto, the constant family's k)
# into $B/gen: the fixed-point step P_kKsS, Newton P_kKsSnewton and, with
# constraints, the poly family's fixed-point step P_kKsSpoly and Newton
# P_kKsSpolynewton. Sets GEN_K to K and GENERATED to their names. A file whose text is unchanged keeps its
# time stamp, so that make does not compile it again.
generate() {
  GEN_K=$("$GEN" --check --multiplier const -s "$2" "$B/models/$1.ham" | sed -n '1s/.* k=\([0-9]*\) s=.*/\1/p')
  _n=${1}_k${GEN_K}s$2
  mkdir -p "$B/gen.new"
  "$GEN" --iteration fixed --multiplier const -k "$GEN_K" -s "$2" -n "$_n" -o "$B/gen.new" "$B/models/$1.ham"
  "$GEN" --iteration newton --multiplier const -k "$GEN_K" -s "$2" -n "${_n}newton" -o "$B/gen.new" "$B/models/$1.ham"
  GENERATED="$_n ${_n}newton"
  if has_constraints "$1"; then
    "$GEN" --iteration fixed --multiplier poly -k "$GEN_K" -s "$2" -n "${_n}poly" -o "$B/gen.new" "$B/models/$1.ham"
    "$GEN" --iteration newton --multiplier poly -k "$GEN_K" -s "$2" -n "${_n}polynewton" -o "$B/gen.new" \
      "$B/models/$1.ham"
    GENERATED="$GENERATED ${_n}poly ${_n}polynewton"
  fi
  for _f in "$B"/gen.new/*; do
    cmp -s "$_f" "$B/gen/${_f##*/}" || mv "$_f" "$B/gen/"
  done
  rm -f "$B"/gen.new/*
}

# One line of a method on a problem with $B/bench (h or the tolerance over
# RANGE, down to the slow error $FLOOR), rows into OUTDIR/work_precision.csv.
sweep() { # outdir problem method range [options]
  _o=$1 _p=$2 _m=$3 _r=$4
  shift 4
  "$B/bench" sweep "$_p" "$_m" "$_o" "$B/ref_$_p.txt" "$_r" --floor "$FLOOR" --keep-going "$@" 2>>"$_o/failures.txt" ||
    echo "   ($_m on $_p: see $_o/failures.txt)"
}
