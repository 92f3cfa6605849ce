#!/bin/sh
# Cargo's runner for `cargo test` in .ci/run: runs each test binary with libtest's
# `--report-time`, so every test's line ends in its seconds (`test name ... ok <1.234s>`), for
# tools/slowest_tests.sh.
#
#   cargo test --release --config "target.'cfg(all())'.runner='$PWD/tools/report_time.sh'"
#
# `--report-time` is unstable: libtest takes it only where RUSTC_BOOTSTRAP is set in the test
# binary's own environment (any value). Set for the whole `cargo test` instead, it would also
# reach the build scripts of proc-macro2 and thiserror, which watch it and switch on nightly
# features: cargo rebuilds nearly every crate, and again at the next command without it. A
# runner changes no build. Only cargo's test harnesses (target/<profile>/deps/) get the flag;
# anything else cargo runs through the runner (rustdoc's compiled doctests) runs as it is.
case "$1" in
*/deps/*)
  bin=$1
  shift
  RUSTC_BOOTSTRAP=1 exec "$bin" -Z unstable-options --report-time "$@"
  ;;
*) exec "$@" ;;
esac
