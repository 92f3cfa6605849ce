//! What the integration tests share: running the binary and reading its outputs, reading the
//! files it writes, the meshes and legs the tests use, and the one proptest configuration.

pub mod files;
pub mod fixtures;
pub mod long;
pub mod process;
pub mod prop_config;
pub mod variants;

pub use files::{base64, exact_json, float, point, read_ply, rust_files};
pub use fixtures::{
    edited_glb, edited_sample, grid_surface, leg_as_ply, load_sample, procedural_leg,
    read_glb_meshes, revolved, sample, sample_legs, solve_on, write_mesh, write_meshes,
    write_raw_meshes, write_tube_leg, RawMesh, FEET,
};
pub use process::{
    files_in, fit, knitfit, knitfit_env, knitfit_within, read_fit_report, read_patch_report,
    read_render_report, read_report_file, run_scene, scene_for, shared_fit, stage_names, stderr,
    stdout, write, OPEN_TUBE,
};
