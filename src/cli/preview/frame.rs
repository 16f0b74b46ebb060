//! One frame of the preview window: the chosen view of the image scaled to fit, the tiles
//! being traced outlined in their worker's colour, optionally one level of BVH boxes, and a
//! panel of statistics and keys below. Drawn on the CPU into 8-bit RGB (text and lines with
//! plotters, in the bundled font) and handed to the window as 0RGB words.

use super::super::progress::{duration, eta, human_rate, spp_done};
use super::picture::{Picture, View};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

/// Height of the statistics panel under the image, in pixels.
pub const PANEL: u32 = 78;

/// The window's smallest width: the panel's lines fit in it.
pub const MIN_WIDTH: u32 = 900;

const TEXT: u32 = 14;
const BACKGROUND: RGBColor = RGBColor(32, 32, 36);
const INK: RGBColor = RGBColor(230, 230, 230);
const DIM: RGBColor = RGBColor(150, 150, 160);

/// What the user has chosen with the keys, and what the window caches for it.
pub struct Controls {
    pub view: View,
    /// Stops of exposure for the beauty view.
    pub exposure: f32,
    pub tiles: bool,
    /// The BVH level whose boxes are drawn, if any, and the tree's depth.
    pub level: Option<u32>,
    pub max_level: u32,
    /// The boxes of `level` as edges in image pixels, and how many boxes.
    pub edges: Vec<[(f32, f32); 2]>,
    pub boxes: usize,
    /// Where the window says it is: scene and device.
    pub title: String,
    /// The last thing a key did (`saved render.beauty.png`).
    pub note: String,
}

/// Where the image lies in a window of `size`: offset and drawn size, in window pixels.
/// Small images are scaled up by a whole factor (crisp pixels), large ones down to fit.
pub fn layout(picture: (u32, u32), size: (u32, u32)) -> (u32, u32, u32, u32) {
    let (w, h) = picture;
    let area = (size.0.max(1), size.1.saturating_sub(PANEL).max(1));
    let fit = (area.0 as f64 / w as f64).min(area.1 as f64 / h as f64);
    let scale = if fit >= 1.0 { fit.floor() } else { fit };
    let (dw, dh) = (
        ((w as f64 * scale) as u32).max(1),
        ((h as f64 * scale) as u32).max(1),
    );
    (
        (area.0 - dw.min(area.0)) / 2,
        (area.1 - dh.min(area.1)) / 2,
        dw,
        dh,
    )
}

/// A worker's colour: golden-angle hues, so neighbouring indices differ.
fn worker_colour(worker: usize) -> HSLColor {
    HSLColor((worker as f64 * 0.381_966 + 0.05) % 1.0, 0.95, 0.55)
}

/// Draws a frame of `size` into `out` (0RGB words, row by row).
pub fn draw(picture: &Picture, controls: &Controls, size: (u32, u32), out: &mut [u32]) {
    let (ww, wh) = size;
    let mut rgb = vec![0u8; 3 * ww as usize * wh as usize];
    let (ox, oy, dw, dh) = layout((picture.width, picture.height), size);
    let (img, range) = picture.image(controls.view, controls.exposure);
    // Background, then the image by nearest sampling.
    for px in rgb.chunks_exact_mut(3) {
        px.copy_from_slice(&[BACKGROUND.0, BACKGROUND.1, BACKGROUND.2]);
    }
    let cols: Vec<usize> = (0..dw)
        .map(|x| {
            ((x as u64 * picture.width as u64 / dw as u64) as usize).min(picture.width as usize - 1)
        })
        .collect();
    for y in 0..dh.min(wh) {
        let sy = ((y as u64 * picture.height as u64 / dh as u64) as usize)
            .min(picture.height as usize - 1);
        let row = &img[sy * picture.width as usize..][..picture.width as usize];
        let start = 3 * ((oy + y) as usize * ww as usize + ox as usize);
        for (x, &sx) in cols.iter().enumerate().take((ww - ox) as usize) {
            rgb[start + 3 * x..start + 3 * x + 3].copy_from_slice(&row[sx]);
        }
    }
    // Text needs the font registered; it is bundled, so this does not fail in practice,
    // and a frame without text is still a frame.
    let _ = register_font("sans-serif", FontStyle::Normal, meshtrace::figures::FONT);
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        let to_window = |x: f32, y: f32| {
            (
                ox as i32 + (x * dw as f32 / picture.width as f32) as i32,
                oy as i32 + (y * dh as f32 / picture.height as f32) as i32,
            )
        };
        if controls.level.is_some() {
            for [a, b] in &controls.edges {
                let _ = root.draw(&PathElement::new(
                    vec![to_window(a.0, a.1), to_window(b.0, b.1)],
                    RGBColor(255, 200, 40).stroke_width(1),
                ));
            }
        }
        if controls.tiles {
            for (&worker, (r, _)) in &picture.active {
                let (a, b) = (
                    to_window(r.x0 as f32, r.y0 as f32),
                    to_window(r.x1 as f32, r.y1 as f32),
                );
                let _ = root.draw(&Rectangle::new(
                    [a, (b.0 - 1, b.1 - 1)],
                    worker_colour(worker).stroke_width(2),
                ));
            }
        }
        panel(&root, picture, controls, range, size);
        let _ = root.present();
    }
    for (dst, px) in out.iter_mut().zip(rgb.chunks_exact(3)) {
        *dst = (px[0] as u32) << 16 | (px[1] as u32) << 8 | px[2] as u32;
    }
}

/// The statistics, the keys and, for depth and cost, the colour scale.
fn panel(
    root: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    picture: &Picture,
    controls: &Controls,
    range: Option<(f32, f32)>,
    (ww, wh): (u32, u32),
) {
    let top = wh.saturating_sub(PANEL) as i32;
    let _ = root.draw(&Rectangle::new(
        [(0, top), (ww as i32, wh as i32)],
        RGBColor(18, 18, 20).filled(),
    ));
    let line = |k: i32| top + 6 + k * (TEXT as i32 + 4);
    let text = |s: String, x: i32, y: i32, colour: &RGBColor| {
        let _ = root.draw(&Text::new(
            s,
            (x, y),
            ("sans-serif", TEXT as f64).into_font().color(colour),
        ));
    };
    let elapsed = match &picture.ended {
        Some((_, at)) => *at - picture.start,
        None => picture.start.elapsed(),
    };
    let total = picture.pixels() * picture.spp as u64;
    // While running: the recent rates and the ETA they give; once ended, the whole
    // render's mean rates.
    let seconds = elapsed.as_secs_f64().max(1e-9);
    let (samples, rays, left) = match picture.ended {
        Some(_) => (
            picture.samples_done as f64 / seconds,
            picture.rays_done as f64 / seconds,
            "ended".to_string(),
        ),
        None => (
            picture.samples_per_second,
            picture.rays_per_second,
            format!(
                "ETA {}",
                eta(picture.samples_done, total, picture.samples_per_second)
            ),
        ),
    };
    text(
        format!(
            "{}    {}    {}    {}    {}    {left}",
            controls.title,
            spp_done(picture.samples_done, picture.pixels(), picture.spp),
            human_rate(samples, "samples"),
            human_rate(rays, "rays"),
            duration(elapsed.as_secs_f64()),
        ),
        8,
        line(0),
        &INK,
    );
    let level = match controls.level {
        Some(l) => format!(
            "level {l} of {} ({} box{})",
            controls.max_level,
            controls.boxes,
            if controls.boxes == 1 { "" } else { "es" }
        ),
        None => "off".into(),
    };
    text(
        format!(
            "view {} [1-5, Tab]    exposure {:+.1} [ ] ]    tiles {} [t]    BVH boxes {level} [b, -, +]    save [s]    close [Esc]",
            controls.view.name(),
            controls.exposure,
            if controls.tiles { "on" } else { "off" },
        ),
        8,
        line(1),
        &DIM,
    );
    let status = match &picture.ended {
        Some((what, _)) => what.clone(),
        None if picture.active.is_empty() => "waiting for the next pass".into(),
        None => picture
            .active
            .iter()
            .map(|(w, (r, s))| {
                if r.x0 == 0 && r.x1 == picture.width {
                    format!("rows {}..{} samples {}..{}", r.y0, r.y1, s.start, s.end)
                } else {
                    format!("thread {w}: tile ({}, {})", r.x0, r.y0)
                }
            })
            .collect::<Vec<_>>()
            .join("   "),
    };
    text(status, 8, line(2), &INK);
    let mut x = 8;
    if let Some((lo, hi)) = range {
        // The colour scale of depth (near white, far dark) or cost (viridis).
        let bar = 200;
        for i in 0..bar {
            let t = i as f32 / (bar - 1) as f32;
            let c = match controls.view {
                View::BvhCost => meshtrace::figures::viridis(t),
                _ => [(40.0 + 215.0 * (1.0 - t)).round() as u8; 3],
            };
            let _ = root.draw(&Rectangle::new(
                [(x + i, line(3) + 2), (x + i + 1, line(3) + TEXT as i32 - 2)],
                RGBColor(c[0], c[1], c[2]).filled(),
            ));
        }
        let what = match controls.view {
            View::BvhCost => "nodes + triangles per camera ray",
            _ => "depth along the view axis",
        };
        let digits = if controls.view == View::BvhCost { 0 } else { 3 };
        text(
            format!("{lo:.digits$} .. {hi:.digits$}  {what}"),
            x + bar + 8,
            line(3),
            &DIM,
        );
        x += bar + 330;
    }
    text(controls.note.clone(), x, line(3), &DIM);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_images_scale_up_by_whole_factors_and_large_ones_fit() {
        // 256x256 in a 900x(600 + panel) window: twice, centred.
        let (ox, oy, dw, dh) = layout((256, 256), (900, 600 + PANEL));
        assert_eq!((dw, dh), (512, 512));
        assert_eq!((ox, oy), ((900 - 512) / 2, (600 - 512) / 2));
        let (_, _, dw, dh) = layout((4000, 2000), (1000, 500 + PANEL));
        assert_eq!((dw, dh), (1000, 500));
    }
}
