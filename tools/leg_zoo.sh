#!/usr/bin/env bash
# The whole leg zoo (tests/integration/zoo.rs, docs/TESTING.md): every variant fitted by the
# release binary, then its table copied into docs/ZOO.md. Fails, after writing the table, when a
# variant that should fit does not.
set -uo pipefail
cd "$(dirname "$0")/.."
KNITFIT_LONG=1 cargo test --release --locked -- zoo::the_whole_zoo_fits_every_leg_it_should \
  --include-ignored --nocapture
status=$?
{
  echo "# The leg zoo"
  echo
  echo "Every variant of \`tests/integration/zoo.rs\` fitted by the binary at the defaults, made by"
  echo "\`tools/leg_zoo.sh\` at $(git rev-parse --short HEAD) on $(nproc) cores. What the forms, mesh"
  echo "forms and frames are, and what a variant is held to: the module doc there and"
  echo "[TESTING.md](TESTING.md#the-leg-zoo)."
  echo
  cat target/zoo/all.md
} >docs/ZOO.md
exit "$status"
