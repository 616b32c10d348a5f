# bench/mq/solvers.sh - sourced by bench/mq/wp.sh and bench/mq/fourbar.sh
# (from the repository's root): a scratch directory $dir, removed on exit,
# the generator $G, the empty $dir/solvers.def and $dir/solvers.h that the
# script fills with one S(name, ...) line and one #include per solver, and
# solver_sources, the generated NAME.c of every solver in solvers.def.
set -e
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
G=gen/hbvmgen
: >"$dir/solvers.def"
: >"$dir/solvers.h"
solver_sources() {
  sed -n 's/^S(\([a-z0-9_]*\),.*/\1.c/p' "$dir/solvers.def" | sed "s|^|$dir/|"
}
