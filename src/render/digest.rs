//! The identity of a render, for the parts of one render to recognise each other: a
//! SHA-256 digest of everything that decides its pixels except the sample range.

use super::gpu::params::Params;
use super::gpu::tables::TABLES;
use super::job::RenderJob;
use super::tables::RenderScene;
use sha2::{Digest, Sha256};

/// The digest, in hex, of `scene` as the renderers read it (every table in binding order,
/// and the camera, sky and environment parameters) and of the job's settings (size, spp,
/// depth, seed), AOVs and transparency. The camera and sky enter through the GPU's
/// parameter block, which both renderers' inputs determine.
pub fn render_digest(scene: &RenderScene, job: &RenderJob) -> String {
    let mut h = Sha256::new();
    h.update(b"meshtrace render digest 1\n");
    for table in TABLES {
        let bytes = (table.bytes)(scene);
        h.update(table.what.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    let params =
        Params::for_scene(scene).with_settings(&scene.camera, &job.settings, &scene.bounds());
    h.update(bytemuck::bytes_of(&params));
    let s = &job.settings;
    for v in [
        s.width,
        s.height,
        s.spp,
        s.max_depth,
        s.seed,
        job.aovs,
        job.transparent as u32,
    ] {
        h.update(v.to_le_bytes());
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}
