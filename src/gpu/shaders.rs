//! SPIR-V of every `glsl/**/*.comp`, compiled by `build.rs` and embedded as
//! `u32` words (so no alignment trap from `include_bytes!`).

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
