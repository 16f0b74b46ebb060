//! A render request: everything that decides an image beyond the input itself — size,
//! samples, depth, seed, branches, caustics, the device, adapter and accel, the AOVs,
//! transparency, a bare mesh's up axis, an environment or a lighting preset that replaces the
//! sky, the largest texture size, the part of a split render, denoising and the view
//! transform. Every source
//! fills the same type: command-line flags, a batch manifest's `[render]` table
//! (deserialised straight into it) and library callers.
//! A field left `None` keeps what the input says (a scene file's own `[render]` table), or
//! the default. [`RenderRequest::validate`] is the one check, and its errors name the field
//! as the manifest spells it (`max_depth`), for the caller to place (`--max-depth`,
//! `render.max_depth`).

use crate::film::{Aov, BitDepth, ViewTransform};
use crate::render::backend::{Backend, DeviceChoice};
use crate::render::gpu::{Accel, GpuError};
use crate::scene::lighting::Lighting;
use crate::scene::studio::{BareOptions, Up};
use crate::scene::{BounceLimits, RenderSettings};
use serde::{Deserialize, Deserializer};
use std::path::PathBuf;

/// What a render asks for; see the module comment.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderRequest {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    /// Longest path in segments from the camera (1 = emitters seen directly).
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    /// Whether to trace caustic light subpaths.
    pub caustics: Option<bool>,
    /// Paths each camera sample branches into at its first hit.
    pub branches: Option<u32>,
    /// The side in pixels of the square a pixel's camera samples fall in (1; 0 for its
    /// centre alone).
    pub filter_width: Option<f32>,
    /// The most diffuse, glossy and transmission bounces of a path, as Cycles' settings of
    /// those names limit them ([`BounceLimits`]).
    pub diffuse_bounces: Option<u32>,
    pub glossy_bounces: Option<u32>,
    pub transmission_bounces: Option<u32>,
    /// `auto` (a hardware GPU, else the CPU), `cpu` or `gpu`.
    #[serde(default, deserialize_with = "device")]
    pub device: Option<DeviceChoice>,
    /// A GPU adapter: an index or a name substring from `meshtrace adapters`.
    pub adapter: Option<String>,
    /// How the GPU finds ray hits: `auto`, `software` or `hardware`.
    #[serde(default, deserialize_with = "accel")]
    pub accel: Option<Accel>,
    /// The AOVs to write beside the radiance (`["depth", "normal"]`).
    #[serde(default, deserialize_with = "aovs")]
    pub aov: Option<Vec<Aov>>,
    /// Whether camera rays that miss are transparent (alpha is the coverage).
    pub transparent: Option<bool>,
    /// A bare mesh's up axis (`x`, `y` or `z`); detected when unset.
    #[serde(default, deserialize_with = "up")]
    pub up: Option<Up>,
    /// An equirectangular image (.hdr, .exr) that lights the scene instead of its sky.
    pub environment: Option<PathBuf>,
    /// A lighting preset that replaces the input's sky and lights (with `environment`, an
    /// error: both set the sky).
    pub lighting: Option<Lighting>,
    /// The most texels a texture may have along its larger side: larger images are scaled
    /// down once loaded ([`Textures::limit_size`](crate::scene::Textures::limit_size)), so
    /// that a scene whose texel table is too large for a GPU renders on it.
    pub max_texture_size: Option<u32>,
    /// Part `index` of `count` of the samples, for a render split across processes
    /// (`render --part`); a batch splits by `--shard` instead.
    #[serde(skip)]
    pub part: Option<Part>,
    /// Whether to denoise the image with Open Image Denoise (the `denoise` feature).
    pub denoise: Option<bool>,
    /// Bits per channel of PNG outputs: 8 (the default) or 16.
    pub bit_depth: Option<u32>,
    /// How 8- and 16-bit outputs are formed from the radiance: `standard` (the sRGB
    /// curve, the default), or Blender's `filmic` or `agx`.
    #[serde(default, deserialize_with = "view_transform")]
    pub view_transform: Option<ViewTransform>,
    /// Whether to trace camera rays alone, for the AOVs (depth, normal, masks) without
    /// path tracing: the image is then the first surface's base colour, unlit.
    pub geometry_only: Option<bool>,
    /// A bare mesh without the studio (its ground and environment): a batch preset lights
    /// it itself.
    #[serde(skip)]
    pub without_studio: bool,
}

/// One part of a split render: samples `PartHeader::range(index, count, spp)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    pub index: u32,
    pub count: u32,
}

/// A request that cannot be rendered: the field (as a manifest key) and why.
#[derive(Debug, thiserror::Error)]
#[error("{field}: {message}")]
pub struct RequestError {
    pub field: &'static str,
    pub message: String,
}

impl RequestError {
    fn new(field: &'static str, message: impl Into<String>) -> Self {
        Self {
            field,
            message: message.into(),
        }
    }
}

/// The `denoise` field's answer in a build without Open Image Denoise.
#[cfg(not(feature = "denoise"))]
pub const NO_DENOISE: &str = "needs a build with Open Image Denoise: `pip install pyoidn==2.5.1.0`, \
     set OIDN_DIR to its pyoidn/oidn folder, then `cargo build --release --features denoise` \
     (docs/outputs.md, \"Denoising\")";

impl RenderRequest {
    /// This request with every field it leaves unset taken from `under` (a manifest's
    /// `[render]` under the command line's flags).
    pub fn over(&self, under: &RenderRequest) -> RenderRequest {
        let r = self.clone();
        let u = under.clone();
        RenderRequest {
            width: r.width.or(u.width),
            height: r.height.or(u.height),
            spp: r.spp.or(u.spp),
            max_depth: r.max_depth.or(u.max_depth),
            seed: r.seed.or(u.seed),
            caustics: r.caustics.or(u.caustics),
            branches: r.branches.or(u.branches),
            filter_width: r.filter_width.or(u.filter_width),
            diffuse_bounces: r.diffuse_bounces.or(u.diffuse_bounces),
            glossy_bounces: r.glossy_bounces.or(u.glossy_bounces),
            transmission_bounces: r.transmission_bounces.or(u.transmission_bounces),
            device: r.device.or(u.device),
            adapter: r.adapter.or(u.adapter),
            accel: r.accel.or(u.accel),
            aov: r.aov.or(u.aov),
            transparent: r.transparent.or(u.transparent),
            up: r.up.or(u.up),
            environment: r.environment.or(u.environment),
            lighting: r.lighting.or(u.lighting),
            max_texture_size: r.max_texture_size.or(u.max_texture_size),
            part: r.part.or(u.part),
            denoise: r.denoise.or(u.denoise),
            bit_depth: r.bit_depth.or(u.bit_depth),
            view_transform: r.view_transform.or(u.view_transform),
            geometry_only: r.geometry_only.or(u.geometry_only),
            without_studio: r.without_studio || u.without_studio,
        }
    }

    /// The input's own settings with the ones this request sets laid over them, checked.
    pub fn settings(&self, own: RenderSettings) -> Result<RenderSettings, RequestError> {
        let s = RenderSettings {
            width: self.width.unwrap_or(own.width),
            height: self.height.unwrap_or(own.height),
            spp: self.spp.unwrap_or(own.spp),
            max_depth: self.max_depth.unwrap_or(own.max_depth),
            seed: self.seed.unwrap_or(own.seed),
            caustics: self.caustics.unwrap_or(own.caustics),
            branches: self.branches.or(own.branches),
            filter_width: self.filter_width.unwrap_or(own.filter_width),
            bounces: BounceLimits {
                diffuse: self.diffuse_bounces.or(own.bounces.diffuse),
                glossy: self.glossy_bounces.or(own.bounces.glossy),
                transmission: self.transmission_bounces.or(own.bounces.transmission),
            },
        };
        s.validate()
            .map_err(|(field, message)| RequestError::new(field, message))?;
        if let Some(p) = self.part
            && p.count > s.spp
        {
            return Err(RequestError::new(
                "part",
                format!(
                    "{} parts of {} spp would leave some empty; use at most {} parts",
                    p.count, s.spp, s.spp
                ),
            ));
        }
        Ok(s)
    }

    /// Checks what can be checked before the input is read: the settings it gives (against
    /// the defaults for those it leaves to the input) and how its fields combine.
    pub fn validate(&self) -> Result<(), RequestError> {
        let own = RenderSettings {
            spp: self.part.map_or(1, |p| p.count),
            ..RenderSettings::default()
        };
        // The size alone is checked once the input's own is known.
        let sized = RenderRequest {
            width: self.width.or(Some(1)),
            height: self.height.or(Some(1)),
            ..self.clone()
        };
        sized.settings(own)?;
        if let Some(Part { index, count }) = self.part
            && (count == 0 || index >= count)
        {
            return Err(RequestError::new(
                "part",
                format!("{index}/{count}: K must be below N, and N at least 1"),
            ));
        }
        if let Some(bits) = self.bit_depth
            && bits != 8
            && bits != 16
        {
            return Err(RequestError::new(
                "bit_depth",
                format!("must be 8 or 16 (bits per channel of a PNG), got {bits}"),
            ));
        }
        if self.environment.is_some() && self.lighting.is_some() {
            return Err(RequestError::new(
                "lighting",
                "cannot be combined with `environment`: both set the sky (a lighting preset \
                 `hdri` takes an image)",
            ));
        }
        if self.max_texture_size == Some(0) {
            return Err(RequestError::new(
                "max_texture_size",
                "must be at least 1 (texels along a texture's larger side), got 0",
            ));
        }
        if self.part.is_some() && self.denoise() {
            return Err(RequestError::new(
                "denoise",
                "applies to a whole image: denoise when merging the parts, not in a part",
            ));
        }
        if self.part.is_some() && self.view_transform() != ViewTransform::Standard {
            return Err(RequestError::new(
                "view_transform",
                "forms an image, and a part holds sums: give it to `meshtrace merge`",
            ));
        }
        if self.geometry_only() && self.denoise() {
            return Err(RequestError::new(
                "denoise",
                "a geometry-only render has no noise to remove; drop one of the two",
            ));
        }
        if self.device == Some(DeviceChoice::Cpu) && self.accel == Some(Accel::Hardware) {
            return Err(RequestError::new(
                "accel",
                "--accel hardware needs the GPU renderer; drop --device cpu or use --accel auto",
            ));
        }
        #[cfg(not(feature = "denoise"))]
        if self.denoise() {
            return Err(RequestError::new("denoise", NO_DENOISE));
        }
        Ok(())
    }

    /// The AOVs the output holds, as a mask ([`Aov::mask`]).
    pub fn aov_mask(&self) -> u32 {
        self.aov.as_deref().map_or(0, Aov::mask)
    }

    pub fn transparent(&self) -> bool {
        self.transparent.unwrap_or(false)
    }

    /// The bit depth of PNG outputs.
    pub fn bit_depth(&self) -> BitDepth {
        match self.bit_depth {
            Some(16) => BitDepth::Sixteen,
            _ => BitDepth::Eight,
        }
    }

    pub fn view_transform(&self) -> ViewTransform {
        self.view_transform.unwrap_or_default()
    }

    pub fn denoise(&self) -> bool {
        self.denoise.unwrap_or(false)
    }

    pub fn geometry_only(&self) -> bool {
        self.geometry_only.unwrap_or(false)
    }

    /// How a bare mesh is staged.
    pub fn bare_options(&self) -> BareOptions {
        BareOptions {
            up: self.up,
            unlit: self.without_studio,
        }
    }

    /// The renderer this request asks for, opened; with, when the CPU was chosen for want
    /// of a usable GPU, a notice saying why.
    pub fn backend(&self) -> Result<(Backend, Option<String>), GpuError> {
        Backend::choose(
            self.device.unwrap_or(DeviceChoice::Auto),
            self.adapter.as_deref(),
            self.accel.unwrap_or(Accel::Auto),
        )
    }
}

/// One of `names`' values by its name, for a manifest's string fields.
/// The value `text` names in `names`, or a message listing the names there are.
pub fn parse_name<T: Copy>(text: &str, names: &[(&str, T)]) -> Result<T, String> {
    names
        .iter()
        .find(|(n, _)| *n == text)
        .map(|&(_, v)| v)
        .ok_or_else(|| {
            let valid: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
            format!("`{text}` is not one of {}", valid.join(", "))
        })
}

/// The names of the [`RenderRequest::device`] choices.
pub const DEVICES: [(&str, DeviceChoice); 3] = [
    ("auto", DeviceChoice::Auto),
    ("cpu", DeviceChoice::Cpu),
    ("gpu", DeviceChoice::Gpu),
];

/// The names of the [`RenderRequest::accel`] choices.
pub const ACCELS: [(&str, Accel); 3] = [
    ("auto", Accel::Auto),
    ("software", Accel::Software),
    ("hardware", Accel::Hardware),
];

fn named<'de, D: Deserializer<'de>, T: Copy>(
    d: D,
    names: &[(&str, T)],
) -> Result<Option<T>, D::Error> {
    let text = String::deserialize(d)?;
    parse_name(&text, names)
        .map(Some)
        .map_err(serde::de::Error::custom)
}

fn device<'de, D: Deserializer<'de>>(d: D) -> Result<Option<DeviceChoice>, D::Error> {
    named(d, &DEVICES)
}

fn accel<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Accel>, D::Error> {
    named(d, &ACCELS)
}

fn up<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Up>, D::Error> {
    named(d, &[("x", Up::X), ("y", Up::Y), ("z", Up::Z)])
}

fn view_transform<'de, D: Deserializer<'de>>(d: D) -> Result<Option<ViewTransform>, D::Error> {
    named(d, &ViewTransform::NAMES)
}

fn aovs<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<Aov>>, D::Error> {
    let names = Vec::<String>::deserialize(d)?;
    Aov::parse_list(&names.join(","))
        .map(Some)
        .map_err(serde::de::Error::custom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_win_over_a_manifest() {
        let manifest = RenderRequest {
            spp: Some(8),
            width: Some(10),
            ..Default::default()
        };
        let flags = RenderRequest {
            spp: Some(16),
            ..Default::default()
        };
        let r = flags.over(&manifest);
        assert_eq!((r.spp, r.width, r.height), (Some(16), Some(10), None));
    }

    #[test]
    fn every_check_names_its_field() {
        let bad = |r: RenderRequest| r.validate().unwrap_err().field;
        let with = |f: fn(&mut RenderRequest)| {
            let mut r = RenderRequest::default();
            f(&mut r);
            r
        };
        assert_eq!(bad(with(|r| r.spp = Some(0))), "spp");
        assert_eq!(bad(with(|r| r.max_depth = Some(0))), "max_depth");
        assert_eq!(bad(with(|r| r.branches = Some(65))), "branches");
        assert_eq!(bad(with(|r| r.width = Some(0))), "width");
        assert_eq!(
            bad(with(|r| r.max_texture_size = Some(0))),
            "max_texture_size"
        );
        assert!(
            with(|r| r.max_texture_size = Some(1)).validate().is_ok(),
            "1 texel is a size"
        );
        assert_eq!(
            bad(with(|r| r.part = Some(Part { index: 2, count: 2 }))),
            "part"
        );
        assert_eq!(
            bad(with(|r| {
                r.device = Some(DeviceChoice::Cpu);
                r.accel = Some(Accel::Hardware);
            })),
            "accel"
        );
        assert!(RenderRequest::default().validate().is_ok());
    }

    #[test]
    fn a_manifest_table_fills_it() {
        let r: RenderRequest = toml::from_str(
            "spp = 4\ncaustics = false\nbranches = 2\ndevice = \"cpu\"\naccel = \"software\"\naov = [\"normal\", \"depth\"]\nup = \"z\"\nenvironment = \"sky.hdr\"\nmax_texture_size = 2048\n",
        )
        .unwrap();
        assert_eq!(r.spp, Some(4));
        assert_eq!(r.caustics, Some(false));
        assert_eq!(r.device, Some(DeviceChoice::Cpu));
        assert_eq!(r.accel, Some(Accel::Software));
        assert_eq!(r.aov, Some(vec![Aov::Depth, Aov::Normal]));
        assert_eq!(r.up, Some(Up::Z));
        assert_eq!(r.max_texture_size, Some(2048));
        let unknown = toml::from_str::<RenderRequest>("sp = 4").unwrap_err();
        assert!(unknown.message().contains("unknown field"), "{unknown}");
        let bad = toml::from_str::<RenderRequest>("device = \"tpu\"").unwrap_err();
        assert!(
            bad.message().contains("`tpu` is not one of auto, cpu, gpu"),
            "{bad}"
        );
    }
}
