//! glTF materials as meshtrace `pbr` materials: the metallic-roughness factors and
//! textures (or KHR_materials_pbrSpecularGlossiness's), the normal and emissive maps, the
//! alpha mode, and KHR_materials_ior, _specular, _transmission, _volume, _clearcoat,
//! _sheen and _emissive_strength; KHR_materials_unlit as the `unlit` kind; texture
//! references with KHR_texture_transform, and images from EXT_texture_webp and
//! KHR_texture_basisu. Each material is converted when a primitive first uses it; one
//! that uses another KHR material extension is warned of by name.

use super::buffers::Buffers;
use super::container::{MATERIAL_EXTENSION, SUPPORTED_EXTENSIONS};
use crate::scene::material::{MAT_ALPHA_MASK, MAT_SPEC_GLOSS, MAT_THIN_WALLED};
use crate::scene::texture::{TextureRef, Usage, UvTransform, Wrap};
use crate::scene::{Material, MaterialKind, NO_TEXTURE, SceneError};
use glam::Vec3;
use gltf::json;
use gltf::json::validation::Checked;
use serde::Deserialize;

/// KHR_materials_clearcoat, which the `gltf` crate leaves as JSON.
#[derive(Deserialize, Default)]
#[serde(default, rename_all = "camelCase")]
struct Clearcoat {
    clearcoat_factor: f32,
    clearcoat_texture: Option<json::texture::Info>,
    clearcoat_roughness_factor: f32,
    clearcoat_roughness_texture: Option<json::texture::Info>,
    clearcoat_normal_texture: Option<json::material::NormalTexture>,
}

/// KHR_materials_sheen, which the `gltf` crate leaves as JSON.
#[derive(Deserialize, Default)]
#[serde(default, rename_all = "camelCase")]
struct Sheen {
    sheen_color_factor: [f32; 3],
    sheen_color_texture: Option<json::texture::Info>,
    sheen_roughness_factor: f32,
    sheen_roughness_texture: Option<json::texture::Info>,
}

/// The materials the primitives read so far use, converted, with their textures.
pub(super) struct Materials<'b, 'a> {
    buffers: &'b Buffers<'a>,
    /// For each glTF material, its index in `materials` once converted.
    converted: Vec<Option<u32>>,
    /// The index of glTF's default material, once a primitive without one needs it.
    default: Option<u32>,
    pub materials: Vec<Material>,
    pub names: Vec<String>,
    pub textures: Vec<TextureRef>,
}

/// A texture reference as the file gives it: a `textureInfo` (or a `normalTexture`).
struct Info<'j> {
    index: usize,
    tex_coord: u32,
    transform: Option<&'j json::extensions::texture::TextureTransform>,
}

impl<'j> From<&'j json::texture::Info> for Info<'j> {
    fn from(info: &'j json::texture::Info) -> Self {
        Self {
            index: info.index.value(),
            tex_coord: info.tex_coord,
            transform: info
                .extensions
                .as_ref()
                .and_then(|e| e.texture_transform.as_ref()),
        }
    }
}

impl<'b, 'a> Materials<'b, 'a> {
    pub fn new(buffers: &'b Buffers<'a>) -> Self {
        Self {
            buffers,
            converted: vec![None; buffers.doc().root.materials.len()],
            default: None,
            materials: Vec::new(),
            names: Vec::new(),
            textures: Vec::new(),
        }
    }

    /// The index in [`Materials::materials`] of glTF material `material` (`None`: the
    /// specification's default material), converting it on first use. `at` is the JSON
    /// path of the primitive that uses it.
    pub fn index(&mut self, material: Option<usize>, at: &str) -> Result<u32, SceneError> {
        let Some(i) = material else {
            if let Some(d) = self.default {
                return Ok(d);
            }
            // The specification's default: white, fully metallic, fully rough.
            let mat = Material {
                metallic: 1.0,
                roughness: 1.0,
                ..Material::new(MaterialKind::PBR)
            };
            let d = self.push(mat, "default (glTF)".into());
            self.default = Some(d);
            return Ok(d);
        };
        let doc = self.buffers.doc();
        match self.converted.get(i) {
            Some(Some(index)) => return Ok(*index),
            Some(None) => {}
            None => {
                return Err(doc.error(
                    format!("{at}.material"),
                    format!(
                        "material {i} does not exist (the file has {})",
                        super::count(doc.root.materials.len(), "material")
                    ),
                ));
            }
        }
        let json = &doc.root.materials[i];
        let mat = self.convert(i, json)?;
        let name = json
            .name
            .clone()
            .unwrap_or_else(|| format!("materials[{i}]"));
        let index = self.push(mat, name);
        self.converted[i] = Some(index);
        Ok(index)
    }

    fn push(&mut self, mat: Material, name: String) -> u32 {
        self.materials.push(mat);
        self.names.push(name);
        self.materials.len() as u32 - 1
    }

    /// Converts material `i`.
    fn convert(&mut self, i: usize, m: &json::Material) -> Result<Material, SceneError> {
        let doc = self.buffers.doc();
        let at = format!("materials[{i}]");
        let mut mat = Material::new(MaterialKind::PBR);
        let ext = m.extensions.as_ref();
        match ext.and_then(|e| e.pbr_specular_glossiness.as_ref()) {
            Some(sg) => {
                let at = format!("{at}.extensions.KHR_materials_pbrSpecularGlossiness");
                self.specular_glossiness(&mut mat, sg, &at)?;
            }
            None => self.metallic_roughness(&mut mat, &m.pbr_metallic_roughness, &at)?,
        }
        if let Some(normal) = &m.normal_texture {
            (mat.normal_texture, mat.normal_scale) =
                self.normal_map(normal, &format!("{at}.normalTexture"))?;
        }
        let mut emission = Vec3::from(m.emissive_factor.0);
        for (k, e) in emission.to_array().into_iter().enumerate() {
            if !(e.is_finite() && e >= 0.0) {
                return Err(doc.error(
                    format!("{at}.emissiveFactor"),
                    format!("component {k} must be finite and at least 0, got {e}"),
                ));
            }
        }
        if let Some(info) = &m.emissive_texture {
            let at = format!("{at}.emissiveTexture");
            mat.emission_texture = self.texture(info.into(), &at, Usage::Colour)?;
        }
        match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Opaque) => {}
            Checked::Valid(json::material::AlphaMode::Mask) => {
                mat.flags |= MAT_ALPHA_MASK;
                let cutoff = m.alpha_cutoff.map_or(0.5, |c| c.0);
                mat.alpha_cutoff = self.unit(cutoff, &format!("{at}.alphaCutoff"))?;
            }
            Checked::Valid(json::material::AlphaMode::Blend) => {
                doc.warn(
                    format!("{at}.alphaMode"),
                    "BLEND is rendered as MASK with an alphaCutoff of 0.5",
                );
                mat.flags |= MAT_ALPHA_MASK;
                mat.alpha_cutoff = 0.5;
            }
            Checked::Invalid => {
                return Err(doc.error(format!("{at}.alphaMode"), "is not OPAQUE, MASK or BLEND"));
            }
        }
        if let Some(ext) = &m.extensions {
            let at = format!("{at}.extensions");
            if let Some(s) = &ext.emissive_strength {
                let at = format!("{at}.KHR_materials_emissive_strength.emissiveStrength");
                let strength = self.finite(s.emissive_strength.0, &at)?;
                if strength < 0.0 {
                    return Err(doc.error(at, format!("must be at least 0, got {strength}")));
                }
                emission *= strength;
            }
            if let Some(ior) = &ext.ior {
                let at = format!("{at}.KHR_materials_ior.ior");
                let ior = self.finite(ior.ior.0, &at)?;
                if ior == 0.0 {
                    doc.warn(&at, "an ior of 0 is not supported; 1.5 is used");
                } else if ior < 1.0 {
                    return Err(doc.error(at, format!("must be at least 1, got {ior}")));
                } else {
                    mat.ior = ior;
                }
            }
            if let Some(s) = &ext.specular {
                let at = format!("{at}.KHR_materials_specular");
                mat.specular = self.unit(s.specular_factor.0, &format!("{at}.specularFactor"))?;
                let color = Vec3::from(s.specular_color_factor.0);
                if !(color.is_finite() && color.min_element() >= 0.0) {
                    return Err(doc.error(
                        format!("{at}.specularColorFactor"),
                        format!("must be finite and at least 0, got {color}"),
                    ));
                }
                mat.specular_color = color;
                if let Some(info) = &s.specular_texture {
                    let at = format!("{at}.specularTexture");
                    mat.specular_texture =
                        self.texture(info.into(), &at, Usage::Scalar { channel: 3 })?;
                }
                if let Some(info) = &s.specular_color_texture {
                    let at = format!("{at}.specularColorTexture");
                    mat.specular_color_texture = self.texture(info.into(), &at, Usage::Colour)?;
                }
            }
            if let Some(t) = &ext.transmission {
                let at = format!("{at}.KHR_materials_transmission");
                mat.transmission =
                    self.unit(t.transmission_factor.0, &format!("{at}.transmissionFactor"))?;
                if let Some(info) = &t.transmission_texture {
                    let at = format!("{at}.transmissionTexture");
                    mat.transmission_texture =
                        self.texture(info.into(), &at, Usage::Scalar { channel: 0 })?;
                }
                // Without a volume of some thickness, the surface is a thin wall.
                let thick = ext
                    .volume
                    .as_ref()
                    .is_some_and(|v| v.thickness_factor.0 > 0.0);
                if !thick {
                    mat.flags |= MAT_THIN_WALLED;
                }
            }
            if let Some(v) = &ext.volume {
                let at = format!("{at}.KHR_materials_volume");
                if v.attenuation_distance.0.is_finite() || v.attenuation_color.0 != [1.0; 3] {
                    doc.warn(at, "attenuation is not supported; the volume is clear");
                }
            }
            if let Some(value) = ext.others.get("KHR_materials_clearcoat") {
                let at = format!("{at}.KHR_materials_clearcoat");
                self.clearcoat(&mut mat, value, &at)?;
            }
            if let Some(value) = ext.others.get("KHR_materials_sheen") {
                let at = format!("{at}.KHR_materials_sheen");
                self.sheen(&mut mat, value, &at)?;
            }
            for name in ext.others.keys() {
                if name.starts_with(MATERIAL_EXTENSION)
                    && !SUPPORTED_EXTENSIONS.contains(&name.as_str())
                {
                    doc.warn(
                        format!("{at}.{name}"),
                        "is not supported; the material is rendered without it",
                    );
                }
            }
            if ext.unlit.is_some() {
                // Only the base colour (and its alpha) is read; the surface reflects
                // nothing and emits nothing but what the camera sees of it.
                mat.kind = MaterialKind::UNLIT;
                emission = Vec3::ZERO;
                mat.emission_texture = NO_TEXTURE;
            }
        }
        mat.emission = emission;
        Ok(mat)
    }

    /// The core metallic-roughness parameters at `at`.pbrMetallicRoughness.
    fn metallic_roughness(
        &mut self,
        mat: &mut Material,
        pbr: &json::material::PbrMetallicRoughness,
        at: &str,
    ) -> Result<(), SceneError> {
        let pbr_at = format!("{at}.pbrMetallicRoughness");
        let [r, g, b, a] = pbr.base_color_factor.0;
        let base = format!("{pbr_at}.baseColorFactor");
        mat.albedo = self.unit3([r, g, b], &base)?;
        mat.alpha = self.unit(a, &base)?;
        mat.metallic = self.unit(pbr.metallic_factor.0, &format!("{pbr_at}.metallicFactor"))?;
        mat.roughness = self.unit(pbr.roughness_factor.0, &format!("{pbr_at}.roughnessFactor"))?;
        if let Some(info) = &pbr.base_color_texture {
            let at = format!("{pbr_at}.baseColorTexture");
            mat.albedo_texture = self.texture(info.into(), &at, Usage::Colour)?;
        }
        if let Some(info) = &pbr.metallic_roughness_texture {
            // Roughness in green, metallic in blue.
            let at = format!("{pbr_at}.metallicRoughnessTexture");
            mat.roughness_texture = self.texture(info.into(), &at, Usage::Scalar { channel: 1 })?;
            mat.metallic_texture = self.texture(info.into(), &at, Usage::Scalar { channel: 2 })?;
        }
        Ok(())
    }

    /// KHR_materials_pbrSpecularGlossiness at `at`, in place of the metallic-roughness
    /// parameters: the diffuse colour as the base colour, under a dielectric whose Fresnel
    /// is Schlick's of F0 = the specular colour ([`MAT_SPEC_GLOSS`]), with roughness
    /// 1 − glossiness. The specular-glossiness texture gives the specular colour (RGB,
    /// sRGB) and the glossiness (alpha, linear).
    fn specular_glossiness(
        &mut self,
        mat: &mut Material,
        sg: &json::extensions::material::PbrSpecularGlossiness,
        at: &str,
    ) -> Result<(), SceneError> {
        let [r, g, b, a] = sg.diffuse_factor.0;
        let diffuse = format!("{at}.diffuseFactor");
        mat.albedo = self.unit3([r, g, b], &diffuse)?;
        mat.alpha = self.unit(a, &diffuse)?;
        mat.specular_color = self.unit3(sg.specular_factor.0, &format!("{at}.specularFactor"))?;
        mat.flags |= MAT_SPEC_GLOSS;
        mat.metallic = 0.0;
        let gloss = self.unit(sg.glossiness_factor.0, &format!("{at}.glossinessFactor"))?;
        mat.roughness = 1.0 - gloss;
        if let Some(info) = &sg.diffuse_texture {
            let at = format!("{at}.diffuseTexture");
            mat.albedo_texture = self.texture(info.into(), &at, Usage::Colour)?;
        }
        if let Some(info) = &sg.specular_glossiness_texture {
            let at = format!("{at}.specularGlossinessTexture");
            mat.specular_color_texture = self.texture(info.into(), &at, Usage::Colour)?;
            mat.roughness_texture = self.texture(info.into(), &at, Usage::Scalar { channel: 3 })?;
        }
        Ok(())
    }

    /// KHR_materials_clearcoat at `at`: the coat's weight (texture: red), roughness
    /// (texture: green) and normal map.
    fn clearcoat(
        &mut self,
        mat: &mut Material,
        value: &serde_json::Value,
        at: &str,
    ) -> Result<(), SceneError> {
        let c: Clearcoat = self.extension(value, at)?;
        mat.clearcoat = self.unit(c.clearcoat_factor, &format!("{at}.clearcoatFactor"))?;
        mat.clearcoat_roughness = self.unit(
            c.clearcoat_roughness_factor,
            &format!("{at}.clearcoatRoughnessFactor"),
        )?;
        if let Some(info) = &c.clearcoat_texture {
            let at = format!("{at}.clearcoatTexture");
            mat.clearcoat_texture = self.texture(info.into(), &at, Usage::Scalar { channel: 0 })?;
        }
        if let Some(info) = &c.clearcoat_roughness_texture {
            let at = format!("{at}.clearcoatRoughnessTexture");
            mat.clearcoat_roughness_texture =
                self.texture(info.into(), &at, Usage::Scalar { channel: 1 })?;
        }
        if let Some(normal) = &c.clearcoat_normal_texture {
            (mat.clearcoat_normal_texture, mat.clearcoat_normal_scale) =
                self.normal_map(normal, &format!("{at}.clearcoatNormalTexture"))?;
        }
        Ok(())
    }

    /// KHR_materials_sheen at `at`: the sheen's colour (texture: RGB, sRGB) and roughness
    /// (texture: alpha).
    fn sheen(
        &mut self,
        mat: &mut Material,
        value: &serde_json::Value,
        at: &str,
    ) -> Result<(), SceneError> {
        let s: Sheen = self.extension(value, at)?;
        mat.sheen_color = self.unit3(s.sheen_color_factor, &format!("{at}.sheenColorFactor"))?;
        mat.sheen_roughness = self.unit(
            s.sheen_roughness_factor,
            &format!("{at}.sheenRoughnessFactor"),
        )?;
        if let Some(info) = &s.sheen_color_texture {
            let at = format!("{at}.sheenColorTexture");
            mat.sheen_color_texture = self.texture(info.into(), &at, Usage::Colour)?;
        }
        if let Some(info) = &s.sheen_roughness_texture {
            let at = format!("{at}.sheenRoughnessTexture");
            mat.sheen_roughness_texture =
                self.texture(info.into(), &at, Usage::Scalar { channel: 3 })?;
        }
        Ok(())
    }

    /// An extension object the `gltf` crate leaves as JSON, read as `T`; one that does not
    /// match is an error naming `at`.
    fn extension<T: serde::de::DeserializeOwned>(
        &self,
        value: &serde_json::Value,
        at: &str,
    ) -> Result<T, SceneError> {
        T::deserialize(value).map_err(|e| {
            self.buffers.doc().error(
                at,
                format!("is malformed: {}", e.to_string().escape_debug()),
            )
        })
    }

    /// A normal map at `at` (a `normalTextureInfo`): its texture slot and the scale of its
    /// XY.
    fn normal_map(
        &mut self,
        normal: &json::material::NormalTexture,
        at: &str,
    ) -> Result<(u32, f32), SceneError> {
        let doc = self.buffers.doc();
        let scale = self.finite(normal.scale, &format!("{at}.scale"))?;
        let transform = normal_transform(normal, at).map_err(|(at, m)| doc.error(at, m))?;
        let info = Info {
            index: normal.index.value(),
            tex_coord: normal.tex_coord,
            transform: transform.as_ref(),
        };
        Ok((self.texture(info, at, Usage::Linear)?, scale))
    }

    /// A factor that must lie in [0, 1]: one outside is clamped, with a warning; one that
    /// is not finite is an error.
    fn unit(&self, x: f32, at: &str) -> Result<f32, SceneError> {
        let x = self.finite(x, at)?;
        if !(0.0..=1.0).contains(&x) {
            self.buffers
                .doc()
                .warn(at, format!("{x} is outside [0, 1] and is clamped"));
        }
        Ok(x.clamp(0.0, 1.0))
    }

    /// Three factors that must lie in [0, 1], as [`Materials::unit`] checks each.
    fn unit3(&self, [r, g, b]: [f32; 3], at: &str) -> Result<Vec3, SceneError> {
        Ok(Vec3::new(
            self.unit(r, at)?,
            self.unit(g, at)?,
            self.unit(b, at)?,
        ))
    }

    fn finite(&self, x: f32, at: &str) -> Result<f32, SceneError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self
                .buffers
                .doc()
                .error(at, format!("must be finite, got {x}")))
        }
    }

    /// The slot of a texture reference in [`Materials::textures`], or `NO_TEXTURE` when
    /// its image is a file that cannot be read (a warning).
    fn texture(&mut self, info: Info, at: &str, usage: Usage) -> Result<u32, SceneError> {
        let doc = self.buffers.doc();
        let Some(texture) = doc.root.textures.get(info.index) else {
            return Err(doc.error(
                format!("{at}.index"),
                format!(
                    "texture {} does not exist (the file has {})",
                    info.index,
                    super::count(doc.root.textures.len(), "texture")
                ),
            ));
        };
        let wrap = texture
            .sampler
            .map_or([Wrap::REPEAT; 2], |s| self.sampler_wrap(s.value()));
        let mut transform = UvTransform::scale(1.0, 1.0);
        let mut tex_coord = info.tex_coord;
        if let Some(t) = info.transform {
            let at = format!("{at}.extensions.KHR_texture_transform");
            let values = [
                t.offset.0[0],
                t.offset.0[1],
                t.rotation.0,
                t.scale.0[0],
                t.scale.0[1],
            ];
            if values.iter().any(|x| !x.is_finite()) {
                return Err(doc.error(at, "offset, rotation and scale must be finite"));
            }
            transform = UvTransform {
                scale: t.scale.0,
                rotation: t.rotation.0,
                offset: t.offset.0,
            };
            tex_coord = t.tex_coord.unwrap_or(tex_coord);
        }
        // Sets 0 and 1 are read; a texture on another set reads set 0.
        let uv_set = if tex_coord > 1 {
            doc.warn(
                at,
                format!("TEXCOORD_{tex_coord} is not supported (only TEXCOORD_0 and TEXCOORD_1 are); TEXCOORD_0 is used"),
            );
            0
        } else {
            tex_coord
        };
        let (source, source_at) =
            image_of(texture, info.index).map_err(|(at, m)| doc.error(at, m))?;
        let Some(source) = self.buffers.image(source, &source_at)? else {
            return Ok(NO_TEXTURE);
        };
        self.textures.push(TextureRef {
            source,
            usage,
            transform,
            wrap,
            optional: false,
            uv_set,
        });
        Ok(self.textures.len() as u32 - 1)
    }

    /// A sampler's wrap modes along u (`wrapS`) and v (`wrapT`). Its filters are not
    /// read: lookups are always bilinear.
    fn sampler_wrap(&self, s: usize) -> [Wrap; 2] {
        use json::texture::WrappingMode as W;
        let Some(sampler) = self.buffers.doc().root.samplers.get(s) else {
            return [Wrap::REPEAT; 2];
        };
        [sampler.wrap_s, sampler.wrap_t].map(|w| match w {
            Checked::Valid(W::ClampToEdge) => Wrap::CLAMP,
            Checked::Valid(W::MirroredRepeat) => Wrap::MIRROR,
            _ => Wrap::REPEAT,
        })
    }
}

/// The extensions through which a texture names an image in a format a core glTF viewer
/// need not read, in the order they are preferred where a texture has several: WebP (as a
/// rule the less lossy), then KTX2 with Basis Universal data.
const IMAGE_EXTENSIONS: [&str; 2] = ["EXT_texture_webp", "KHR_texture_basisu"];

/// The image texture `index` reads, with the JSON path that names it: the image of its
/// `EXT_texture_webp` or `KHR_texture_basisu` extension where it has one (preferred over
/// the fallback `source` that both extensions let a file keep for viewers without them),
/// else its own `source`. A texture with neither is an error.
fn image_of(texture: &json::Texture, index: usize) -> Result<(usize, String), (String, String)> {
    let at = format!("textures[{index}]");
    let extension = IMAGE_EXTENSIONS.iter().find_map(|&name| {
        let value = texture.extensions.as_ref()?.others.get(name)?;
        Some((name, value))
    });
    if let Some((name, extension)) = extension {
        let at = format!("{at}.extensions.{name}.source");
        return match extension
            .get("source")
            .map(|s| s.as_u64().map(usize::try_from))
        {
            Some(Some(Ok(source))) => Ok((source, at)),
            Some(_) => Err((at, "must be an image index (an integer ≥ 0)".into())),
            None => Err((at, "is required but missing".into())),
        };
    }
    // The `gltf` crate's mark of a texture without `source` (its `allow_empty_texture`).
    let source = texture.source.value();
    if source == u32::MAX as usize {
        return Err((
            format!("{at}.source"),
            "is missing, and the texture names no EXT_texture_webp or KHR_texture_basisu \
             image instead"
                .into(),
        ));
    }
    Ok((source, format!("{at}.source")))
}

/// A normal texture's KHR_texture_transform, which the `gltf` crate leaves as JSON.
fn normal_transform(
    normal: &json::material::NormalTexture,
    at: &str,
) -> Result<Option<json::extensions::texture::TextureTransform>, (String, String)> {
    let Some(value) = normal
        .extensions
        .as_ref()
        .and_then(|e| e.others.get("KHR_texture_transform"))
    else {
        return Ok(None);
    };
    json::deserialize::from_value(value.clone())
        .map(Some)
        .map_err(|e| {
            (
                format!("{at}.extensions.KHR_texture_transform"),
                format!("is malformed: {}", e.to_string().escape_debug()),
            )
        })
}
