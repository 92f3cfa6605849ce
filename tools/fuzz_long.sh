#!/usr/bin/env bash
# Long fuzz runs, for overnight: every fuzz target, far past the default suite's case counts.
#
#   tools/fuzz_long.sh [CASES] [PROCESS_CASES] [SHARD]
#
# CASES (default 100000) is each proptest fuzz test's case count, through PROPTEST_CASES: the
# leg loader on damaged GLB/glTF files, on damaged PLY files, the scene parser on damaged scenes,
# and the two PLY writers (tests/integration/fuzz.rs). PROCESS_CASES (default CASES / 100) is the
# number of damaged files run through the `knitfit` binary itself, through
# KNITFIT_PROCESS_FUZZ_CASES (tests/integration/process_fuzz.rs: exit codes, one-line refusals,
# nothing written, a time bound per run). Every case comes from the suite's fixed seed, so a run
# with more cases tries the same cases first and then new ones; a failure prints its minimal
# input, to be kept as a named regression_… test. SHARD (default 0, the suite's own cases) picks
# another fixed stream of cases (KNITFIT_FUZZ_SHARD; tests/integration/support/prop_config.rs),
# so runs on several machines or nights add up to new inputs: docs/fuzz_runs.md records the
# shards run and their totals. To isolate a process-fuzz failure, see the
# KNITFIT_PROCESS_FUZZ_FROM / _KIND / _KEEP / _TIME_BOUND_S / _VERBOSE variables at the top of
# tests/integration/process_fuzz.rs.
#
# Rough rates on 2 shared cores, release build: the five proptest targets together 3,000 to
# 5,000 cases a second, the process target about 10 runs a second. Ten million inputs in all:
# CASES=2000000 (five targets) is about an hour.
#
# Runs under nice; exits non-zero on the first target that fails.
set -euo pipefail
cd "$(dirname "$0")/.."
cases="${1:-100000}"
process_cases="${2:-$((cases / 100))}"
export KNITFIT_FUZZ_SHARD="${3:-0}"
start=$(date +%s)
echo "fuzz_long: shard ${KNITFIT_FUZZ_SHARD}: ${cases} cases per proptest fuzz target, ${process_cases} process runs"
PROPTEST_CASES="$cases" nice -n 10 cargo test --release --test integration -- fuzz:: --skip process_fuzz
KNITFIT_PROCESS_FUZZ_CASES="$process_cases" nice -n 10 cargo test --release --test integration -- process_fuzz --nocapture
echo "fuzz_long: shard ${KNITFIT_FUZZ_SHARD} done in $(($(date +%s) - start)) s: ${cases} × 5 proptest cases and ${process_cases} process runs passed"
