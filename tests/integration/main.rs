//! lacuna's integration tests, one module per subject, in one test binary:
//! cargo links and runs it once, and its tests from every subject share the
//! machine's cores (test binaries run one after another, so a binary's last
//! long test used to leave a core idle). `cargo test NAME` filters by
//! `module::test` as before; `cargo test bricks::` runs one subject.

mod common;
// The embedding example's host-side helpers (storage images, buffers),
// shared by the tests that play a host engine.
#[path = "../../examples/embed/host.rs"]
mod host;

mod architecture;
mod auto;
mod bench;
mod bricks;
mod built_for;
mod cells;
mod channels;
mod cli;
mod cli_look;
mod distance;
mod embed;
mod export;
mod fuzz_inputs;
mod gpu_core;
mod hardening;
mod host_depth;
mod host_render;
mod identity;
mod identity_modes;
mod kd;
mod lbvh;
mod leaves;
mod modes;
mod mpi;
mod nan;
mod octree;
mod parallel;
mod prims;
mod registry;
mod render_naive;
mod series;
mod soundness;
mod stream;
mod stream_files;
mod transfer_function;
mod value_range;
mod view;
mod volumes;
