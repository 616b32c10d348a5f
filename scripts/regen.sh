#!/bin/sh
# Regenerate every solver listed in generated/LIST into DIR (default generated).
#   scripts/regen.sh [HBVMGEN] [DIR]
set -eu
gen=${1:-gen/hbvmgen}
dir=${2:-generated}
mkdir -p "$dir"
grep -v '^#' generated/LIST | while read -r model k s flags; do
  [ -n "$model" ] || continue
  # shellcheck disable=SC2086
  "$gen" -k "$k" -s "$s" -n "${model}_k${k}s${s}" -o "$dir" $flags "models/$model.ham"
done
