# bench/common.sh - sourced by bench/run.sh, bench/adaptive/run.sh,
# bench/stiff/run.sh and the plot scripts: the
# range of fixed steps of each problem, the error where a line stops, and the
# registry of the generated solvers of a build.
# Step sizes FROM:TO:FACTOR (h = T/N, N from ceil(T/FROM) doubling) and the
# error at which a line stops (the reference's accuracy).
hrange() {
  case $1 in
  pendulum) echo 0.5:1e-5:2 ;;
  conical) echo 1:1e-4:2 ;;
  modified) echo 0.2:1e-5:2 ;;
  satellites) echo 2:1e-3:2 ;;
  kepler*) echo 0.2:1e-4:2 ;;
  chain8) echo 0.02:1e-5:2 ;;
  double_pendulum) echo 0.2:1e-5:2 ;;
  esac
}
floor() {
  case $1 in
  kepler* | conical) echo 1e-13 ;;
  *) echo 3e-13 ;;
  esac
}

# The gnuplot terminal of the figures, $1 pixels ("1100,750"): pngcairo where
# gnuplot has it.
png_terminal() {
  if echo 'set terminal' | gnuplot 2>&1 | grep -q pngcairo; then
    echo "pngcairo size $1 font ',11'"
  else
    echo "png size $1"
  fi
}

# Write DIR/registry.c, the table gen_solvers[] of the solvers named in the
# remaining arguments (bench/hbvm.h), for the script named in $1.
write_registry() { # script dir solver...
  _script=$1 _dir=$2
  shift 2
  {
    echo "/* registry.c - written by $_script: the generated solvers of this build. */"
    echo "#include \"hbvm.h\""
    for n in "$@"; do echo "extern const GenSolver ${n}_bench;"; done
    echo "const GenSolver *const gen_solvers[] = {"
    for n in "$@"; do echo "  &${n}_bench,"; done
    echo "  0};"
  } >"$_dir/registry.c"
}
