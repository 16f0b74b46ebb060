//! BVH figures without a window (`meshtrace info --heatmap`, `--bounds`): the cost of each
//! camera ray as a heat map with a colour bar, and one level of the tree's boxes drawn over a
//! render. Drawn with plotters into an RGB buffer (text in the bundled DejaVu Sans subset,
//! `assets/fonts/`), encoded as PNG by `image` and written as every output is: complete or
//! not at all.

use crate::bvh::BvhNode;
use crate::film::{self, Aov, AovValues, FilmError};
use crate::render::{RenderJob, RenderScene, cpu};
use crate::scene::RenderSettings;
use crate::scene::camera::Camera;
use glam::Vec3;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::Path;

/// The font of every figure's text (and of the preview window's), built into the binary.
pub const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans-subset.ttf");

/// Camera rays per pixel of a heat map, jittered as the renderer jitters them.
pub const HEATMAP_SAMPLES: u32 = 4;

/// Width of the legend beside a heat map, in pixels.
const LEGEND: u32 = 150;

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("{path}: {message}")]
    Draw { path: String, message: String },
    #[error(transparent)]
    Film(#[from] FilmError),
}

/// A figure's pixels: 8-bit RGB, row by row.
struct Canvas {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(width: u32, height: u32, fill: [u8; 3]) -> Self {
        Self {
            width,
            height,
            rgb: fill.repeat(width as usize * height as usize),
        }
    }

    fn set(&mut self, x: u32, y: u32, c: [u8; 3]) {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        self.rgb[i..i + 3].copy_from_slice(&c);
    }

    /// Draws on the canvas with plotters (text, lines, boxes) through `draw`.
    fn draw(
        &mut self,
        path: &Path,
        draw: impl FnOnce(&DrawingArea<BitMapBackend, plotters::coord::Shift>) -> Result<(), String>,
    ) -> Result<(), FigureError> {
        let error = |message: String| FigureError::Draw {
            path: path.display().to_string(),
            message,
        };
        // Registering twice is harmless; the font is valid, so this cannot fail in practice.
        register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| error("the bundled font does not load".into()))?;
        let size = (self.width, self.height);
        let root = BitMapBackend::with_buffer(&mut self.rgb, size).into_drawing_area();
        draw(&root).map_err(error)?;
        root.present().map_err(|e| error(e.to_string()))
    }

    /// Writes the canvas as a PNG, complete or not at all.
    fn save(self, path: &Path) -> Result<(), FigureError> {
        let image =
            image::RgbImage::from_raw(self.width, self.height, self.rgb).ok_or_else(|| {
                FigureError::Draw {
                    path: path.display().to_string(),
                    message: "canvas size mismatch".into(),
                }
            })?;
        let mut bytes = Vec::new();
        image
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .map_err(|e| FigureError::Draw {
                path: path.display().to_string(),
                message: e.to_string(),
            })?;
        Ok(film::write_bytes(path, &bytes)?)
    }
}

/// Viridis, sampled at nine points (matplotlib's), for `t` in [0, 1]: dark blue to yellow,
/// perceptually uniform and readable in grey.
pub fn viridis(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 9] = [
        [68.0, 1.0, 84.0],
        [71.0, 44.0, 122.0],
        [59.0, 81.0, 139.0],
        [44.0, 113.0, 142.0],
        [33.0, 144.0, 141.0],
        [39.0, 173.0, 129.0],
        [92.0, 200.0, 99.0],
        [170.0, 220.0, 50.0],
        [253.0, 231.0, 37.0],
    ];
    let x = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * 8.0;
    let i = (x as usize).min(7);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|k| (a[k] + (b[k] - a[k]) * f + 0.5) as u8)
}

/// The BVH cost (nodes visited plus triangles tested) of each pixel's camera rays: the mean
/// over [`HEATMAP_SAMPLES`] jittered rays, as the `bvh_cost` AOV counts them.
pub fn ray_costs(scene: &RenderScene, settings: &RenderSettings) -> Vec<f32> {
    let film = cpu::first_hits(scene, settings, HEATMAP_SAMPLES, Aov::BvhCost.bit());
    match film.aov_values(Aov::BvhCost).as_deref() {
        Some([AovValues::F32(costs)]) => costs.clone(),
        _ => unreachable!("the film holds the bvh_cost AOV it was made with"),
    }
}

/// Writes the heat map of `costs` (one per pixel of a `width`×`height` image) with a colour
/// bar from 0 to the largest cost, its ticks, and the mean and maximum, to `path` (PNG).
pub fn write_heatmap(
    path: &Path,
    width: u32,
    height: u32,
    costs: &[f32],
) -> Result<(), FigureError> {
    let top = costs.iter().copied().fold(0.0f32, f32::max).max(1.0);
    let mean = costs.iter().map(|&c| c as f64).sum::<f64>() / costs.len().max(1) as f64;
    let (cw, ch) = (width + LEGEND, height.max(200));
    let mut canvas = Canvas::new(cw, ch, [255, 255, 255]);
    for (i, &c) in costs.iter().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        canvas.set(x, y, viridis(c / top));
    }
    // The colour bar: top (largest cost) to bottom (0).
    let (bar_x, bar_top, bar_bottom) = (width + 16, 46u32, ch - 16);
    for y in bar_top..bar_bottom {
        let t = (bar_bottom - 1 - y) as f32 / (bar_bottom - 1 - bar_top) as f32;
        for x in bar_x..bar_x + 18 {
            canvas.set(x, y, viridis(t));
        }
    }
    canvas.draw(path, |root| {
        let font = |size: u32| ("sans-serif", size).into_font().color(&BLACK);
        let text = |s: String, x: u32, y: u32, size: u32| {
            root.draw(&Text::new(s, (x as i32, y as i32), font(size)))
                .map_err(|e| e.to_string())
        };
        text("BVH cost per ray".into(), width + 8, 4, 13)?;
        text("(nodes + triangles)".into(), width + 8, 19, 11)?;
        text(format!("mean {mean:.1}"), bar_x + 24, bar_bottom - 30, 11)?;
        for k in 0..=4 {
            let v = top * k as f32 / 4.0;
            let y = bar_bottom - 1 - ((bar_bottom - 1 - bar_top) * k) / 4;
            root.draw(&PathElement::new(
                vec![(bar_x as i32 + 18, y as i32), (bar_x as i32 + 22, y as i32)],
                BLACK,
            ))
            .map_err(|e| e.to_string())?;
            text(format!("{v:.0}"), bar_x + 25, y.saturating_sub(6), 11)?;
        }
        Ok(())
    })?;
    canvas.save(path)
}

/// The boxes of level `depth` of the tree (the root is level 0), with the leaves above it,
/// so that together they cover every triangle.
pub fn level_boxes(nodes: &[BvhNode], depth: u32) -> Vec<BvhNode> {
    let mut out = Vec::new();
    let mut stack = vec![(0usize, 0u32)];
    while let Some((i, d)) = stack.pop() {
        let Some(node) = nodes.get(i) else { continue };
        if d == depth || node.is_leaf() {
            out.push(*node);
            continue;
        }
        stack.push((node.left_or_first as usize, d + 1));
        stack.push((i + 1, d + 1));
    }
    out
}

/// Where the pinhole `camera` sees point `p` on a `width`×`height` image, in pixels: `None`
/// behind the near plane.
fn project(camera: &Camera, p: Vec3, width: u32, height: u32, near: f32) -> Option<(f32, f32)> {
    let d = p - camera.position;
    let z = d.dot(camera.forward);
    if z < near {
        return None;
    }
    let aspect = width as f32 / height as f32;
    // The view's half height at the point's depth: fixed for an orthographic camera.
    let half = if camera.is_orthographic() {
        0.5 * camera.ortho_height
    } else {
        z * (0.5 * camera.vfov.to_radians()).tan()
    };
    let x = d.dot(camera.right) / (half * aspect);
    let y = d.dot(camera.up) / half;
    Some((
        0.5 * (x + 1.0) * width as f32,
        0.5 * (1.0 - y) * height as f32,
    ))
}

/// The part of segment `a`–`b` inside the rectangle `[0, w] × [0, h]` (Liang–Barsky).
fn clip(a: (f32, f32), b: (f32, f32), w: f32, h: f32) -> Option<((f32, f32), (f32, f32))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [(-dx, a.0), (dx, w - a.0), (-dy, a.1), (dy, h - a.1)] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// The twelve edges of box `node` as seen by `camera`, clipped to the near plane and the
/// image, in pixels.
pub fn box_edges(camera: &Camera, node: &BvhNode, width: u32, height: u32) -> Vec<[(f32, f32); 2]> {
    let b = node.bounds();
    let corner = |k: usize| b.corner(k);
    let near = 1e-4 * (1.0 + b.extent().length());
    let mut out = Vec::new();
    for (i, j) in [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ] {
        let (mut p, mut q) = (corner(i), corner(j));
        // Cut the edge at the near plane where it crosses it.
        let (zp, zq) = (
            (p - camera.position).dot(camera.forward),
            (q - camera.position).dot(camera.forward),
        );
        if zp < near && zq < near {
            continue;
        }
        if zp < near {
            p = q + (p - q) * ((zq - near) / (zq - zp));
        } else if zq < near {
            q = p + (q - p) * ((zp - near) / (zp - zq));
        }
        let (Some(a), Some(c)) = (
            project(camera, p, width, height, near * 0.5),
            project(camera, q, width, height, near * 0.5),
        ) else {
            continue;
        };
        if let Some((a, c)) = clip(a, c, width as f32, height as f32) {
            out.push([a, c]);
        }
    }
    out
}

/// Renders the scene at `settings` on the CPU (at most 16 spp: a backdrop) and draws the
/// boxes of BVH level `depth` over it, each in its own colour, with a caption; writes the
/// PNG to `path`. Returns how many boxes were drawn.
pub fn write_bounds(
    path: &Path,
    scene: &RenderScene,
    settings: &RenderSettings,
    depth: u32,
) -> Result<usize, FigureError> {
    let settings = RenderSettings {
        spp: settings.spp.min(16),
        ..*settings
    };
    let (w, h) = (settings.width, settings.height);
    let backdrop = cpu::render(scene, &RenderJob::new(settings), &|_| {});
    let mut canvas = Canvas::new(w, h, [0, 0, 0]);
    for (i, c) in backdrop.mean().iter().enumerate() {
        // Dimmed, so that the boxes stand out.
        let rgb = c.to_array().map(|v| film::linear_to_srgb8(v * 0.6));
        canvas.set(i as u32 % w, i as u32 / w, rgb);
    }
    let boxes = level_boxes(&scene.bvh.nodes, depth);
    let caption = format!(
        "BVH level {depth}: {} box{}",
        boxes.len(),
        if boxes.len() == 1 { "" } else { "es" }
    );
    canvas.draw(path, |root| {
        for (k, node) in boxes.iter().enumerate() {
            // Golden-angle hues: neighbours in the list get distant colours.
            let colour = HSLColor((k as f64 * 0.381_966) % 1.0, 0.9, 0.6);
            for [a, b] in box_edges(&scene.camera, node, w, h) {
                root.draw(&PathElement::new(
                    vec![(a.0 as i32, a.1 as i32), (b.0 as i32, b.1 as i32)],
                    colour.stroke_width(1),
                ))
                .map_err(|e| e.to_string())?;
            }
        }
        root.draw(&Rectangle::new(
            [(0, 0), (8 * caption.len() as i32 + 8, 20)],
            BLACK.filled(),
        ))
        .map_err(|e| e.to_string())?;
        root.draw(&Text::new(
            caption.clone(),
            (4, 3),
            ("sans-serif", 13).into_font().color(&WHITE),
        ))
        .map_err(|e| e.to_string())
    })?;
    canvas.save(path)?;
    Ok(boxes.len())
}
