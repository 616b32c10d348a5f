# bench/ranges.sh - sourced by bench/run.sh and bench/adaptive/run.sh: the
# range of fixed steps of each problem and the error where a line stops.
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
