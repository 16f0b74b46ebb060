//! The integration tests, one binary: each module is a subject (its file says which). One
//! process shares the GPU context of `common::gpu`, and with it every compiled kernel,
//! across all of them, and links once. `tests/ray_query.rs` and `tests/denoise.rs` stay
//! binaries of their own: CI runs them under another driver and a cargo feature.
//!
//! `cargo test --release --test suite MODULE::` runs one subject.

mod common;

// The algorithm benches' chi-square code includes `common/gamma.rs` by path, as `common` does.
#[allow(clippy::duplicate_mod)]
mod algorithms;
mod alpha_mask;
mod analytic;
mod aovs;
mod batch;
mod bounces;
mod branches;
mod bsdf;
mod bvh;
mod caustics;
mod checked_kernels;
mod cli;
mod deploy;
mod deploy_slurm;
mod environment;
mod figures;
mod fuzz_corpus;
mod gltf;
mod gltf_corpus;
mod gltf_errors;
mod gltf_samples;
mod gltf_validator;
mod gpu_vs_cpu;
mod image_io;
mod imports;
mod layout;
mod lights;
mod mitsuba_references;
mod normal_maps;
mod obj_mtl;
mod orthographic;
mod parts;
mod pbr;
mod preview;
mod properties;
mod scene_format;
mod seed_scene;
mod shader_units;
mod textures;
mod view_transforms;
