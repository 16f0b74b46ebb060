//! `meshtrace info`: a scene's size, lights, textures and BVH, and the optional BVH figures.

use super::{out, pipeline_error, warn};
use anyhow::{Context, Result, bail};
use glam::Vec3;
use meshtrace::bvh::BuildParams;
use meshtrace::film::{Film, Format};
use meshtrace::math::Aabb;
use meshtrace::pipeline;
use meshtrace::render::{LIGHT_EMITTER, RenderScene, SKY_EMITTER};
use meshtrace::request::RenderRequest;
use meshtrace::scene::{Scene, TextureFormat};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct InfoArgs {
    /// Scene file, .obj mesh, .gltf/.glb file, or builtin:NAME.
    pub scene: PathBuf,
    /// Also write a heat map of the BVH cost of each camera ray (nodes visited plus
    /// triangles tested, the mean of 4 jittered rays a pixel) with a colour bar, as a PNG
    /// at the scene's image size.
    #[arg(long, value_name = "FILE")]
    pub heatmap: Option<PathBuf>,
    /// Also draw the BVH's boxes of level DEPTH (the root is 0; leaves above it too) over a
    /// quick render of the scene, as a PNG.
    #[arg(long, num_args = 2, value_names = ["DEPTH", "FILE"])]
    pub bounds: Option<Vec<String>>,
}

pub fn info(args: &InfoArgs) -> Result<()> {
    let path = args.scene.as_path();
    let level = match args.bounds.as_deref() {
        Some([depth, file]) => {
            let depth: u32 = depth.parse().with_context(|| {
                format!("--bounds: `{depth}` is not a tree level (0 is the root)")
            })?;
            Some((depth, PathBuf::from(file)))
        }
        _ => None,
    };
    for out in args.heatmap.iter().chain(level.as_ref().map(|b| &b.1)) {
        if Format::from_path(out)? != Format::Png {
            bail!(
                "{}: figures are written as PNG; give a .png file",
                out.display()
            );
        }
        Film::check_writable(out, false)?;
    }
    let scene = pipeline::load(path, &RenderRequest::default()).map_err(pipeline_error)?;
    for w in &scene.warnings {
        warn(w);
    }
    let rs = RenderScene::new(&scene, &BuildParams::default())?;
    let st = &rs.bvh.stats;
    let name = scene.path.as_deref().unwrap_or(path).display();
    out!("scene        {name}");
    out!("triangles    {}", st.triangles);
    out!("vertices     {}", scene.mesh.positions.len());
    out!("materials    {}", scene.materials.len());
    for note in &scene.notes {
        out!("note         {note}");
    }
    let bounds = rs.bvh.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds());
    if bounds.is_empty() {
        out!("bounds       empty");
    } else {
        let v = |p: Vec3| format!("({:.4}, {:.4}, {:.4})", p.x, p.y, p.z);
        out!("bounds       {} to {}", v(bounds.min), v(bounds.max));
        out!("centre       {}", v(bounds.center()));
        out!("size         {}", v(bounds.extent()));
    }
    let sky = rs.sky_pmf > 0.0;
    let punctual = rs
        .emitters
        .iter()
        .filter(|&&e| e & LIGHT_EMITTER != 0 && e != SKY_EMITTER)
        .count();
    let tris = rs.emitters.len() - punctual - sky as usize;
    out!(
        "emitters     {tris} triangles, {} point, spot, directional or rect lights{}",
        punctual,
        if sky { " and the sky" } else { "" }
    );
    print_textures(&scene)?;
    out!(
        "bvh build    {:.2} ms ({:.2} M triangles/s)",
        st.build_seconds * 1e3,
        st.triangles as f64 / st.build_seconds.max(1e-9) / 1e6
    );
    out!("sah cost     {:.3}", st.sah_cost);
    out!(
        "nodes        {} ({} leaves, {} bytes)",
        st.nodes,
        st.leaves,
        st.nodes * 32
    );
    out!("depth        {}", st.depth);
    let hist: Vec<String> = st
        .leaf_sizes
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| format!("{k}:{n}"))
        .collect();
    out!("leaf sizes   {}", hist.join(" "));
    if let Some(file) = &args.heatmap {
        let s = &scene.settings;
        let costs = meshtrace::figures::ray_costs(&rs, s);
        meshtrace::figures::write_heatmap(file, s.width, s.height, &costs)?;
        let mean = costs.iter().map(|&c| c as f64).sum::<f64>() / costs.len().max(1) as f64;
        let max = costs.iter().copied().fold(0.0f32, f32::max);
        out!(
            "heat map     {} (nodes + triangles per camera ray: mean {mean:.1}, max {max:.0})",
            file.display()
        );
    }
    if let Some((depth, file)) = &level {
        let n = meshtrace::figures::write_bounds(file, &rs, &scene.settings, *depth)?;
        out!("bounds       {} (level {depth}: {n} boxes)", file.display());
    }
    if let Some(kib) = super::peak_memory_kib() {
        out!("peak memory  {:.1} MiB", kib as f64 / 1024.0);
    }
    Ok(())
}

/// The scene's textures: how many, the distinct images they read, and the memory their
/// texels take (the same on the host and the device), then one line per image.
fn print_textures(scene: &Scene) -> Result<()> {
    let t = &scene.textures;
    let mut images: Vec<(u32, usize)> = Vec::new();
    for (k, r) in t.records.iter().enumerate() {
        if !images.iter().any(|&(offset, _)| offset == r.offset) {
            images.push((r.offset, k));
        }
    }
    out!(
        "textures     {} ({} images, {})",
        t.records.len(),
        images.len(),
        mebibytes(t.texels.len() as u64 * 4)
    );
    for (_, k) in images {
        let r = &t.records[k];
        let (kind, bytes) = if r.format == TextureFormat::RGBA32F {
            ("RGBA 32-bit float", 16)
        } else {
            ("RGBA 8-bit", 4)
        };
        out!(
            "  {}  {}x{} {kind}, {}",
            t.names[k],
            r.width,
            r.height,
            mebibytes(r.width as u64 * r.height as u64 * bytes)
        );
    }
    Ok(())
}

fn mebibytes(bytes: u64) -> String {
    format!("{:.2} MiB", bytes as f64 / (1024.0 * 1024.0))
}
