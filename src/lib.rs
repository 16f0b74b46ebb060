//! meshtrace: a physically based path tracer for triangle meshes.
//!
//! The data flows one way: a scene file is loaded into a [`scene::Scene`], whose triangles
//! a SAH [`bvh::Bvh`] orders and indexes; [`render::RenderScene`] packs both into the flat
//! tables that the CPU renderer ([`render::cpu`]) and the GPU compute renderer
//! ([`render::gpu`]) read alike; the samples land in a [`film::Film`], which writes the
//! image file. With the `denoise` feature, the `denoise` module runs Intel Open Image Denoise over
//! the film before it is written.

pub mod batch;
pub mod bench;
pub mod bvh;
#[cfg(feature = "denoise")]
pub mod denoise;
pub mod figures;
pub mod film;
pub mod fixed;
pub mod geometry;
pub mod math;
pub mod pipeline;
pub mod render;
pub mod request;
pub mod scene;
