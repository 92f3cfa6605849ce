#!/usr/bin/env bash
# The whole leg zoo (tests/integration/zoo.rs, docs/TESTING.md), the posed characters and the
# strides without a rig: every variant fitted by the
# release binary, then its table copied into docs/ZOO.md. Fails, after writing the table, when a
# variant that should fit does not.
set -uo pipefail
cd "$(dirname "$0")/.."
KNITFIT_LONG=1 cargo test --release --locked -- zoo::the_whole_zoo_fits_every_leg_it_should \
  --include-ignored --nocapture
status=$?
KNITFIT_LONG=1 cargo test --release --locked -- rig::the_posed_zoo_fits_every_pose_the_skin_bends_cleanly \
  --include-ignored --nocapture
posed=$?
KNITFIT_LONG=1 cargo test --release --locked -- zoo::the_stride_zoo_table --include-ignored --nocapture
strides=$?
{
  echo "# The leg zoo"
  echo
  echo "Every variant of \`tests/integration/zoo.rs\` fitted by the binary at the defaults, made by"
  echo "\`tools/leg_zoo.sh\` at $(git rev-parse --short HEAD) on $(nproc) cores. What the forms, mesh"
  echo "forms and frames are, and what a variant is held to: the module doc there and"
  echo "[TESTING.md](TESTING.md#the-leg-zoo)."
  echo
  cat target/zoo/all.md
  echo
  echo "## Posed characters"
  echo
  echo "The rigged MakeHuman woman (\`samples/rigged/\`) posed by her joint nodes (her legs, or both"
  echo "arms raised over her head), exported with her"
  echo "skin (rigged) or as the posed mesh alone (baked), her armature as exported, turned to Z up,"
  echo "scaled to centimetres (read with \`--units cm\`) or turned 120° about up"
  echo "(\`tests/integration/rig.rs\`, [decision 0077](decisions/0077-rigged-legs-are-fitted-at-rest-and-carried-into-the-pose.md))."
  echo
  cat target/zoo/posed.md
  echo
  echo "## Strides without a rig"
  echo
  echo "Each left leg of the zoo (of both body models: cut open, closed, slanted, in pieces, the"
  echo "whole mannequin's with its trunk and right leg still; the procedural leg closed, open,"
  echo "slanted, in pieces) posed"
  echo "as a stride with no rig, its knee bent back and its hip flexed forward, or its foot"
  echo "pointed down, by the degrees named (a piece turned whole, a mesh across a joint blended over"
  echo "4 cm), fitted at the defaults (\`zoo::the_stride_zoo_table\`; the bend read is"
  echo "\`details.pose.bend\`, [decision 0077](decisions/0077-rigged-legs-are-fitted-at-rest-and-carried-into-the-pose.md))."
  echo
  cat target/zoo/strides.md
} >docs/ZOO.md
[ "$status" -eq 0 ] && [ "$posed" -eq 0 ] && [ "$strides" -eq 0 ]
