//! Images that must estimate the same expected value: renders of several seeds compared in
//! blocks of pixels, as z scores against the seeds' spread.

use super::stats::mean_and_stderr;
use meshtrace::film::Film;
use meshtrace::render::{RenderJob, RenderScene};
use meshtrace::scene::RenderSettings;

/// The largest |z| a block may show: the seeds' spread is itself estimated from 8 or 16
/// renders (Student's t with 7 or 15 degrees of freedom), over 16 blocks.
pub const Z_MAX: f64 = 6.0;

/// Renders seeds `seeds` of `settings` on the CPU or, with `gpu`, the GPU.
pub fn renders(
    rs: &RenderScene,
    settings: RenderSettings,
    seeds: std::ops::Range<u32>,
    gpu: Option<&meshtrace::render::gpu::GpuContext>,
) -> Vec<Film> {
    seeds
        .map(|seed| {
            let job = RenderJob::new(RenderSettings { seed, ..settings });
            match gpu {
                Some(ctx) => super::gpu_render(ctx, rs, &job),
                None => super::cpu_render(rs, &job),
            }
        })
        .collect()
}

/// Each render's mean of r + g + b over every block of `block` × `block` pixels, with a
/// last entry for the whole image; then per entry the mean over the renders and its
/// standard error.
pub fn block_means(films: &[Film], block: u32) -> Vec<(f64, f64)> {
    let (w, h) = (films[0].width, films[0].height);
    let (bw, bh) = (w / block, h / block);
    let per_film: Vec<Vec<f64>> = films
        .iter()
        .map(|f| {
            let mean = f.mean();
            let mut sums = vec![0.0f64; (bw * bh) as usize];
            for y in 0..bh * block {
                for x in 0..bw * block {
                    let v = mean[(y * w + x) as usize];
                    sums[((y / block) * bw + x / block) as usize] += (v.x + v.y + v.z) as f64;
                }
            }
            let mut means: Vec<f64> = sums.iter().map(|s| s / (block * block) as f64).collect();
            means.push(means.iter().sum::<f64>() / means.len() as f64);
            means
        })
        .collect();
    (0..per_film[0].len())
        .map(|b| {
            let values: Vec<f64> = per_film.iter().map(|v| v[b]).collect();
            mean_and_stderr(&values)
        })
        .collect()
}

/// Fails where a block's mean, or the whole image's, differs between `test` and
/// `reference` by more than `Z_MAX` standard errors of the difference.
pub fn assert_same_image(what: &str, test: &[Film], reference: &[Film], block: u32) {
    let (a, b) = (block_means(test, block), block_means(reference, block));
    let z: Vec<f64> = a
        .iter()
        .zip(&b)
        .map(|((ma, sa), (mb, sb))| (ma - mb) / (sa * sa + sb * sb).sqrt().max(1e-9))
        .collect();
    let (whole, blocks) = z.split_last().unwrap();
    let (worst, at) = blocks
        .iter()
        .enumerate()
        .map(|(k, &z)| (z, k))
        .fold(
            (0.0f64, 0),
            |m, c| if c.0.abs() > m.0.abs() { c } else { m },
        );
    let ((ta, _), (tb, _)) = (a[a.len() - 1], b[b.len() - 1]);
    eprintln!(
        "{what}: {} blocks, worst z {worst:.2} (block {at}); whole image {ta:.5} against {tb:.5} ({:+.2}%, z {whole:.2})",
        blocks.len(),
        100.0 * (ta - tb) / tb,
    );
    assert!(tb > 0.0, "{what}: a black reference proves nothing");
    assert!(
        worst.abs() <= Z_MAX,
        "{what}: block {at} differs by {worst:.2} standard errors"
    );
    assert!(
        whole.abs() <= Z_MAX,
        "{what}: the whole image differs by {whole:.2} standard errors"
    );
}
