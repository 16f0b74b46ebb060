//! `meshtrace merge`: the part files of one render (`render --part K/N`) added into the
//! image of all their samples, bit for bit the image of one render on the same device.

use super::ViewArg;
use anyhow::{Result, bail};
use meshtrace::film::{BitDepth, DisplayTransform, Film, Format, PartHeader};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The part files (.exr), in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output image; the extension picks the format (.png .jpg .bmp .exr .hdr), and the
    /// AOVs the parts hold are written as `render` writes them.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Merge parts rendered on different devices (their sums can differ in the last
    /// bits, so the result is not the bits of any one render).
    #[arg(long)]
    pub allow_mixed_devices: bool,
    /// How a PNG, WebP, JPEG or BMP output is formed from the radiance: `standard`,
    /// `filmic` or `agx`, as `render --view-transform`.
    #[arg(long, value_enum)]
    pub view_transform: Option<ViewArg>,
    /// Print nothing but warnings and errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// A part file read, with its path for messages.
struct Part {
    path: PathBuf,
    film: Film,
    header: PartHeader,
}

pub fn merge(args: &MergeArgs) -> Result<()> {
    Film::check_writable(&args.output, false)?;
    let view = match args.view_transform.map(ViewArg::view) {
        Some(v) => {
            let format = Format::from_path(&args.output)?;
            Film::check_encoding(&args.output, format, BitDepth::Eight, v)?;
            DisplayTransform::load(v)?
        }
        None => DisplayTransform::default(),
    };
    let mut parts = Vec::new();
    for path in &args.parts {
        let (film, header) = Film::read_part(path)?;
        parts.push(Part {
            path: path.clone(),
            film,
            header,
        });
    }
    check_same_render(&parts, args.allow_mixed_devices)?;
    parts.sort_by_key(|p| (p.header.start, p.header.end));
    check_coverage(&parts)?;
    let spp = parts[0].header.spp;
    let mut merged = parts[0].film.clone();
    for p in &parts[1..] {
        merged.merge(&p.film);
    }
    for p in &parts {
        let wanted = p.header.end - p.header.start;
        if p.film.samples < wanted {
            eprintln!(
                "warning: {}: holds {} of its {wanted} samples (its render was interrupted); the image is the mean of the {} samples the parts hold, not of {spp}",
                p.path.display(),
                p.film.samples,
                parts.iter().map(|p| p.film.samples).sum::<u32>(),
            );
        }
    }
    merged.save_as(&args.output, BitDepth::Eight, &view)?;
    if !args.quiet {
        eprintln!(
            "merged {} parts ({} of {spp} spp, {}) -> {}",
            parts.len(),
            merged.samples,
            parts[0].header.device,
            args.output.display()
        );
    }
    Ok(())
}

/// Every part must come from the same scene, settings and (unless allowed) device.
fn check_same_render(parts: &[Part], mixed_devices: bool) -> Result<()> {
    let first = &parts[0];
    let (a, ha) = (first.path.display(), &first.header);
    for p in &parts[1..] {
        let (b, hb) = (p.path.display(), &p.header);
        let size = |f: &Film| (f.width, f.height);
        if size(&first.film) != size(&p.film) {
            bail!(
                "{a} is {}x{} and {b} is {}x{}: parts of different renders",
                first.film.width,
                first.film.height,
                p.film.width,
                p.film.height
            );
        }
        if ha.spp != hb.spp || ha.seed != hb.seed {
            bail!(
                "{a} is of {} spp with seed {} and {b} of {} spp with seed {}: parts of different renders",
                ha.spp,
                ha.seed,
                hb.spp,
                hb.seed
            );
        }
        if ha.digest != hb.digest {
            bail!(
                "{a} and {b} are parts of different scenes or settings (digests {} and {})",
                short(&ha.digest),
                short(&hb.digest)
            );
        }
        if ha.device != hb.device && !mixed_devices {
            bail!(
                "{a} was rendered on {} and {b} on {}; their sums may differ in the last bits, so the merge would match no single render (--allow-mixed-devices merges them anyway)",
                ha.device,
                hb.device
            );
        }
    }
    Ok(())
}

/// The parts, sorted by first sample, must cover the render's samples once each.
fn check_coverage(parts: &[Part]) -> Result<()> {
    let spp = parts[0].header.spp;
    let mut next = 0;
    let mut previous: Option<&Path> = None;
    for p in parts {
        let (start, end) = (p.header.start, p.header.end);
        if start > next {
            bail!(
                "samples {next}..{start} of {spp} are in no part ({}); nothing written",
                listing(parts)
            );
        }
        if start < next {
            bail!(
                "{} and {} overlap (samples {start}..{next}); nothing written",
                previous.map_or(String::new(), |p| p.display().to_string()),
                p.path.display()
            );
        }
        next = end;
        previous = Some(&p.path);
    }
    if next < spp {
        bail!(
            "samples {next}..{spp} of {spp} are in no part ({}); nothing written",
            listing(parts)
        );
    }
    Ok(())
}

/// The parts' files and sample ranges, for messages.
fn listing(parts: &[Part]) -> String {
    parts
        .iter()
        .map(|p| {
            format!(
                "{} has {}..{}",
                p.path.display(),
                p.header.start,
                p.header.end
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The first 12 hex digits of a digest.
fn short(digest: &str) -> &str {
    digest.get(..12).unwrap_or(digest)
}
