//! Rendering: the flat scene tables both devices read ([`RenderScene`], in [`tables`]),
//! laid out from a scene by `build`; the stages of the path tracer, each a Rust file with a
//! WGSL twin of the same name in `shaders/` (`rng`, `sampling`, `bsdf`, `camera`,
//! `texture`, `surface`, `environment`, `lights`, `caustics`, `integrator`), which read
//! those tables; a render [`job`]; and the two drivers that run them, [`cpu`] and [`gpu`],
//! chosen by [`backend`]. The GPU renderer uploads exactly these tables, so a path can be
//! replayed on either device.
//!
//! Imports run one way: the tables depend on no stage, each stage on the tables and on
//! the stages below it, the builder on both, and the drivers on all of them.

pub mod backend;
pub mod bsdf;
mod build;
pub mod camera;
pub mod caustics;
pub mod cpu;
pub mod digest;
pub mod environment;
pub mod gpu;
pub mod integrator;
pub mod job;
pub mod lights;
pub mod rng;
pub mod sampling;
pub mod sheen;
pub mod surface;
pub mod tables;
pub mod texture;
pub mod watch;

pub use job::{CheckpointFn, Checkpoints, RenderJob};
pub use tables::{
    CausticTarget, Environment, LIGHT_DIRECTIONAL, LIGHT_EMITTER, LIGHT_POINT, LIGHT_RECT,
    LIGHT_SPOT, Light, RenderScene, SKY_EMITTER, TRI_COLOR, TRI_SMOOTH, TRI_TANGENT, TRI_UV,
    TRI_UV1, TriColors, TriShading, TriTangents, TriUvs,
};
