#!/bin/sh
# The N slowest tests (default 10) of a `cargo test` log whose test binaries ran with
# `--report-time` (tools/report_time.sh): wall seconds, then the test, after its source file.
#
#   tools/slowest_tests.sh LOG [N]
#
# Each test binary runs after cargo's `Running <source> (<binary>)` line; a test's line is
# `test NAME ... ok <SECONDS s>` (or FAILED). Doctests carry no time. Says so when the log holds
# no times.
set -eu
log=$1
n=${2:-10}
slowest=$(awk '
  /^ *Running / { source = $0; sub(/^ *Running (unittests )?/, "", source); sub(/ .*/, "", source) }
  /^test .* \.\.\. .*<[0-9.]+s>/ {
    line = $0
    gsub(/\033\[[0-9;]*m/, "", line)
    seconds = line; sub(/.*</, "", seconds); sub(/s>.*/, "", seconds)
    name = line; sub(/^test /, "", name); sub(/ \.\.\. .*/, "", name)
    printf "%8.1f s  %s: %s\n", seconds, source, name
  }
' "$log" | sort -rn | head -n "$n")
if [ -n "$slowest" ]; then
  echo "The $n slowest tests (wall seconds; tests run side by side, sharing the cores):"
  echo "$slowest"
else
  echo "No test times in $log: was tools/report_time.sh the test runner?"
fi
