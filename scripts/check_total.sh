#!/bin/sh
# check_total.sh DIR RUN SUITE... - the total of one run of make check or
# check-long, whose suites ran one runner each: DIR/SUITE.log is what the
# runner printed, DIR/SUITE.rc its exit status. Prints the suites that
# failed, then the run's total in Check's own words ("N%: Checks: X,
# Failures: Y, Errors: Z", N as Check computes it); a runner that ended
# without its summary line, or with a nonzero status its summary does not
# explain (a sanitizer report in the runner itself), counts as an error.
# Exit status 0 when every suite passed, 1 otherwise.
set -u
dir=$1 run=$2
shift 2
nsuites=$#
checks=0 failures=0 errors=0 bad=""
for suite in "$@"; do
  rc=$(cat "$dir/$suite.rc" 2>/dev/null || echo missing)
  line=$(grep -E '^[0-9]+%: Checks: [0-9]+, Failures: [0-9]+, Errors: [0-9]+$' "$dir/$suite.log" 2>/dev/null | tail -n 1)
  if [ -z "$line" ]; then
    errors=$((errors + 1))
    bad="$bad $suite"
    echo "$suite: the runner printed no summary (exit status $rc; see $dir/$suite.log)"
    continue
  fi
  read -r _ n f e <<END
$(echo "$line" | sed 's/[^0-9]\{1,\}/ /g')
END
  checks=$((checks + n)) failures=$((failures + f)) errors=$((errors + e))
  if [ "$f" -ne 0 ] || [ "$e" -ne 0 ]; then
    bad="$bad $suite"
  elif [ "$rc" != 0 ]; then
    errors=$((errors + 1))
    bad="$bad $suite"
    echo "$suite: all checks passed but the runner exited with status $rc (see $dir/$suite.log)"
  fi
done
if [ "$failures" -eq 0 ] && [ "$errors" -eq 0 ]; then
  percent=100
elif [ "$checks" -eq 0 ]; then
  percent=0
else
  percent=$(((checks - failures - errors) * 100 / checks))
fi
echo "== make check, $run run: $nsuites suites${bad:+, failed:$bad} (logs in $dir/)"
echo "$percent%: Checks: $checks, Failures: $failures, Errors: $errors"
[ -z "$bad" ]
