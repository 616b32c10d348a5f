#!/bin/sh
# Generate every solver of a list (default generated/LIST) into DIR.
#   scripts/regen.sh [HBVMGEN [DIR [LIST [MODELDIR]]]]
# A list line is "MODEL K S [FLAGS]"; the solver is named MODEL_kKsS and
# generated from MODELDIR/MODEL.ham (MODELDIR defaults to models). MODEL may
# be NAME:FILE, to generate NAME_kKsS from FILE (a path from the top): the
# same model under other flags.
set -eu
gen=${1:-gen/hbvmgen}
dir=${2:-generated}
list=${3:-generated/LIST}
models=${4:-models}
mkdir -p "$dir"
grep -v '^#' "$list" | while read -r model k s flags; do
  [ -n "$model" ] || continue
  name=${model%%:*}
  file="$models/$name.ham"
  case "$model" in *:*) file=${model#*:} ;; esac
  # shellcheck disable=SC2086
  "$gen" -k "$k" -s "$s" -n "${name}_k${k}s${s}" -o "$dir" $flags "$file"
done
