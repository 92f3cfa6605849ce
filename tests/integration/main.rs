//! Integration tests: the physics the paper claims, the command line's contract, and the files.
//! One test binary (see ripgrep); modules by topic.

mod anatomy;
mod cli;
mod contact;
mod docs;
mod evaluation;
mod fit;
mod foot;
mod fuzz;
mod golden;
mod guide;
mod hard_cases;
mod layers;
mod limits;
mod look;
mod physics;
mod plan;
mod process_fuzz;
mod properties;
mod real_stitches;
mod render;
mod report;
mod rig;
mod skin;
mod solvers;
mod support;
mod units;
mod zoo;
