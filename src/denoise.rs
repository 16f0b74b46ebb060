//! Denoising with Intel Open Image Denoise (OIDN), on the CPU: its `RT` filter, made for
//! Monte Carlo path-traced images, over the film's linear HDR radiance, optionally guided
//! by per-pixel albedo and normal images. Only with the `denoise` feature, which links
//! libOpenImageDenoise (README.md, "Denoising (optional)", says how to get it).

use crate::film::{Aov, AovValues, Film};
use glam::Vec3;

/// Why an image could not be denoised.
#[derive(Debug, thiserror::Error)]
pub enum DenoiseError {
    /// An image's pixel count is not the width times the height.
    #[error("denoise: the {image} image has {len} pixels, not {width}x{height}")]
    Size {
        image: &'static str,
        len: usize,
        width: u32,
        height: u32,
    },
    /// OIDN's `RT` filter takes a normal image only together with an albedo image.
    #[error("denoise: a normal guide needs an albedo guide too")]
    NormalWithoutAlbedo,
    /// Open Image Denoise itself failed (no usable CPU device, out of memory, ...).
    #[error("Open Image Denoise: {0}")]
    Oidn(String),
}

/// An Open Image Denoise CPU device. Making one first checks, before a long render, that
/// the library loads and runs on this CPU; one device serves any number of images.
pub struct Denoiser {
    device: oidn::Device,
}

impl Denoiser {
    /// A denoiser on the CPU, with as many threads as OIDN chooses (one per core).
    pub fn new() -> Result<Self, DenoiseError> {
        let device = oidn::Device::cpu().map_err(|e| DenoiseError::Oidn(e.to_string()))?;
        Ok(Self { device })
    }

    /// A denoiser on the CPU that uses at most `threads` threads (`--threads`), so that a
    /// render confined to some cores is denoised on those too.
    pub fn with_threads(threads: usize) -> Result<Self, DenoiseError> {
        use oidn::sys::{
            OIDNDeviceType_OIDN_DEVICE_TYPE_CPU, oidnCommitDevice, oidnNewDevice, oidnSetDeviceInt,
        };
        let threads = i32::try_from(threads).unwrap_or(i32::MAX);
        // SAFETY: a new device is configured before its commit, as OIDN requires, and
        // handed to `Device`, which owns and releases it from then on.
        let device = unsafe {
            let handle = oidnNewDevice(OIDNDeviceType_OIDN_DEVICE_TYPE_CPU);
            if handle.is_null() {
                return Err(DenoiseError::Oidn("cannot create a CPU device".into()));
            }
            oidnSetDeviceInt(handle, c"numThreads".as_ptr(), threads);
            oidnCommitDevice(handle);
            oidn::Device::from_raw(handle)
        };
        device
            .get_error()
            .map_err(|e| DenoiseError::Oidn(e.to_string()))?;
        Ok(Self { device })
    }

    /// The threads the device runs (OIDN's `numThreads`; 0 where it chooses itself).
    pub fn threads(&self) -> i32 {
        // SAFETY: the device is valid while `self` is.
        unsafe { oidn::sys::oidnGetDeviceInt(self.device.raw(), c"numThreads".as_ptr()) }
    }

    /// Denoises `color`, linear HDR radiance of `width` × `height` pixels in rows from the
    /// top, and returns the denoised image of the same size. `albedo` and `normal` are the
    /// optional guides of the same size: the first surface's albedo in [0, 1] and its
    /// shading normal (any length, world or camera space), 0 where no surface was hit.
    /// They may be noisy (OIDN's `cleanAux` off): a film's channels are averages over the
    /// same few samples as the image, noisy where depth of field or glass blurs them.
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[[f32; 3]],
        albedo: Option<&[[f32; 3]]>,
        normal: Option<&[[f32; 3]]>,
    ) -> Result<Vec<[f32; 3]>, DenoiseError> {
        let pixels = width as usize * height as usize;
        let check = |image: &'static str, len: usize| {
            if len == pixels {
                Ok(())
            } else {
                Err(DenoiseError::Size {
                    image,
                    len,
                    width,
                    height,
                })
            }
        };
        check("colour", color.len())?;
        if let Some(a) = albedo {
            check("albedo", a.len())?;
        }
        if let Some(n) = normal {
            check("normal", n.len())?;
        }
        let mut filter = oidn::RayTracing::try_new(&self.device)
            .map_err(|e| DenoiseError::Oidn(e.to_string()))?;
        filter
            .hdr(true)
            .image_dimensions(width as usize, height as usize);
        match (albedo, normal) {
            // Noisy guides (OIDN's default): a few samples a pixel average them. (The crate
            // passes `clean_aux` to OIDN 2 under a name it ignores; setting OIDN's own
            // `cleanAux` made the dataset job's noise worse: BENCHMARKS.md, Denoising.)
            (Some(a), Some(n)) => {
                filter
                    .albedo_normal(bytemuck::cast_slice(a), bytemuck::cast_slice(n))
                    .clean_aux(false);
            }
            (Some(a), None) => {
                filter.albedo(bytemuck::cast_slice(a)).clean_aux(false);
            }
            (None, Some(_)) => return Err(DenoiseError::NormalWithoutAlbedo),
            (None, None) => {}
        }
        let mut out = vec![[0.0f32; 3]; pixels];
        filter
            .filter(
                bytemuck::cast_slice(color),
                bytemuck::cast_slice_mut(&mut out),
            )
            .map_err(|e| DenoiseError::Oidn(e.to_string()))?;
        Ok(out)
    }

    /// Replaces the film's radiance by its denoised mean, keeping its sample count and its
    /// channels, so that [`Film::save`] writes the denoised image. Where the film holds the
    /// `albedo` and `normal` AOVs, they guide the denoiser. A transparent film is denoised
    /// within [`covered_rectangle`] alone: outside it every channel is 0, and stays so.
    pub fn denoise_film(&self, film: &mut Film) -> Result<(), DenoiseError> {
        let [x0, y0, x1, y1] = covered_rectangle(film);
        if x0 >= x1 || y0 >= y1 {
            return Ok(());
        }
        let (w, h, stride) = (x1 - x0, y1 - y0, film.width as usize);
        // Pixel i of the rectangle, as an index of the film.
        let at =
            move |i: usize| (y0 as usize + i / w as usize) * stride + x0 as usize + i % w as usize;
        let crop = |image: Vec<[f32; 3]>| -> Vec<[f32; 3]> {
            (0..(w * h) as usize).map(|i| image[at(i)]).collect()
        };
        let mean = film.mean();
        let color: Vec<[f32; 3]> = crop(mean.iter().map(|c| c.to_array()).collect());
        // The guides, where the film holds them: the albedo AOV, and with it the normal AOV
        // (0 where no sample hit).
        let guide = |aov: Aov| -> Option<Vec<[f32; 3]>> {
            let values = film.aov_values(aov)?;
            let [x, y, z] = [0, 1, 2].map(|k| match values.get(k) {
                Some(AovValues::F32(v)) => Some(v),
                _ => None,
            });
            let (x, y, z) = (x?, y?, z?);
            Some(crop((0..x.len()).map(|i| [x[i], y[i], z[i]]).collect()))
        };
        let albedo = guide(Aov::Albedo);
        let normal = albedo.as_ref().and_then(|_| guide(Aov::Normal));
        let denoised = self.denoise(w, h, &color, albedo.as_deref(), normal.as_deref())?;
        for (i, d) in denoised.iter().enumerate() {
            film.set_mean(at(i), Vec3::from(*d));
        }
        Ok(())
    }
}

/// Pixels of context the denoiser gets around what a transparent film covers: the width
/// of the strides OIDN's network downsamples by, so that its first layers see the edges
/// as in the whole image.
pub const CROP_MARGIN: u32 = 16;

/// The pixels [x0, x1) × [y0, y1) to denoise: for a transparent film, the smallest
/// rectangle holding every pixel its samples covered (alpha > 0), [`CROP_MARGIN`] wider
/// on each side within the film (an empty one where nothing was covered); the whole film
/// otherwise. Outside it a transparent film is 0 in every channel: on a dataset's object
/// a third of the image or less is denoised.
pub fn covered_rectangle(film: &Film) -> [u32; 4] {
    let whole = [0, 0, film.width, film.height];
    let values = film.aov_values(Aov::Alpha);
    let alpha = match values.as_deref() {
        Some([AovValues::F32(a), ..]) if film.transparent => a,
        _ => return whole,
    };
    let (mut lo, mut hi) = ([u32::MAX; 2], [0u32; 2]);
    for (i, &a) in alpha.iter().enumerate() {
        if a > 0.0 {
            let (x, y) = (i as u32 % film.width, i as u32 / film.width);
            lo = [lo[0].min(x), lo[1].min(y)];
            hi = [hi[0].max(x + 1), hi[1].max(y + 1)];
        }
    }
    if lo[0] == u32::MAX {
        return [0; 4];
    }
    [
        lo[0].saturating_sub(CROP_MARGIN),
        lo[1].saturating_sub(CROP_MARGIN),
        (hi[0] + CROP_MARGIN).min(film.width),
        (hi[1] + CROP_MARGIN).min(film.height),
    ]
}
