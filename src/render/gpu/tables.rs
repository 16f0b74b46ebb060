//! What the scene's tables are on the device: each is uploaded (by `upload`) as it lies in
//! memory into an Rgba32Uint texture, [`TABLE_WIDTH`] texels a row; here are the list of
//! tables, the WGSL that loads their structs, and the bind group layout (group 0) that the
//! shaders read them through (`shaders/bindings.wgsl`). A texel fetch is a
//! gather on every device, and a texture of 4096 × 16384 texels holds 1 GiB, far beyond
//! some drivers' limits on a storage binding.

use super::error::TEXEL_TABLE;
use super::layout::{Member, StructLayout, struct_layout};
use super::params::Params;
use crate::bvh::BvhNode;
use crate::geometry::TriVerts;
use crate::render::tables::{
    CausticTarget, Light, RenderScene, TriColors, TriShading, TriTangents, TriUvs,
};
use crate::scene::{Material, Texture};

/// Texels per row of the table textures (the shaders get its log2 from `shader::shared_constants`).
pub const TABLE_WIDTH: u32 = 1 << 12;

/// What a table holds per element.
pub enum Element {
    /// A host-shared struct of a whole number of texels (16 bytes each), none of whose
    /// members straddles two texels.
    Struct(StructLayout),
    /// One 32-bit word, four to a texel.
    U32,
    F32,
}

/// One scene table: what errors call it, its texture and loader in the shaders, its
/// element, and where its bytes lie in a [`RenderScene`]. Bindings follow [`TABLES`]'
/// order, after the parameter block at binding 0.
pub struct Table {
    pub what: &'static str,
    pub texture: &'static str,
    pub loader: &'static str,
    pub element: fn() -> Element,
    pub bytes: for<'a> fn(&'a RenderScene) -> &'a [u8],
}

/// The scene's tables, in binding order. The WGSL bindings and loaders (`load_node`, …)
/// are generated from this list by [`wgsl_tables`].
pub const TABLES: &[Table] = &[
    Table {
        what: "BVH nodes",
        texture: "nodes_tex",
        loader: "load_node",
        element: || {
            Element::Struct(struct_layout!(BvhNode {
                min,
                left_or_first,
                max,
                count
            }))
        },
        bytes: |s| bytemuck::cast_slice(&s.bvh.nodes),
    },
    Table {
        what: "triangles",
        texture: "tris_tex",
        loader: "load_tri",
        element: || Element::Struct(struct_layout!(TriVerts { v0, v1, v2 })),
        bytes: |s| bytemuck::cast_slice(&s.tris),
    },
    Table {
        what: "triangle shading data",
        texture: "shading_tex",
        loader: "load_shading",
        element: || {
            Element::Struct(struct_layout!(TriShading {
                n0,
                material,
                n1,
                emitter_pmf,
                n2,
                flags
            }))
        },
        bytes: |s| bytemuck::cast_slice(&s.shading),
    },
    Table {
        what: "materials",
        texture: "materials_tex",
        loader: "load_material",
        element: || {
            Element::Struct(struct_layout!(Material {
                albedo,
                kind,
                emission,
                roughness,
                specular_color,
                ior,
                metallic,
                specular,
                transmission,
                flags,
                alpha,
                alpha_cutoff,
                normal_scale,
                albedo_texture,
                emission_texture,
                roughness_texture,
                metallic_texture,
                transmission_texture,
                normal_texture,
                specular_color_texture,
                specular_texture,
                clearcoat,
                sheen_color,
                sheen_roughness,
                coat_normal,
                clearcoat_roughness,
                clearcoat_texture,
                clearcoat_roughness_texture,
                clearcoat_normal_texture,
                clearcoat_normal_scale,
                sheen_color_texture,
                sheen_roughness_texture,
                _pad,
            }))
        },
        bytes: |s| bytemuck::cast_slice(&s.materials),
    },
    Table {
        what: "texture coordinates",
        texture: "tri_uvs_tex",
        loader: "load_tri_uvs",
        element: tri_uvs_element,
        bytes: |s| bytemuck::cast_slice(&s.tri_uvs),
    },
    Table {
        what: "tangents",
        texture: "tri_tangents_tex",
        loader: "load_tri_tangents",
        element: || Element::Struct(struct_layout!(TriTangents { t0, t1, t2 })),
        bytes: |s| bytemuck::cast_slice(&s.tri_tangents),
    },
    Table {
        what: "second texture coordinates",
        texture: "tri_uvs1_tex",
        loader: "load_tri_uvs1",
        element: tri_uvs_element,
        bytes: |s| bytemuck::cast_slice(&s.tri_uvs1),
    },
    Table {
        what: "vertex colours",
        texture: "tri_colors_tex",
        loader: "load_tri_colors",
        element: || Element::Struct(struct_layout!(TriColors { c0, c1, c2 })),
        bytes: |s| bytemuck::cast_slice(&s.tri_colors),
    },
    Table {
        what: "textures",
        texture: "textures_tex",
        loader: "load_texture",
        element: || {
            Element::Struct(struct_layout!(Texture {
                offset,
                width,
                height,
                format,
                uv_matrix,
                uv_offset,
                channel,
                wrap,
                uv_set,
                _pad,
            }))
        },
        bytes: |s| bytemuck::cast_slice(&s.textures),
    },
    Table {
        what: TEXEL_TABLE,
        texture: "texels_tex",
        loader: "load_texel",
        element: || Element::U32,
        bytes: |s| bytemuck::cast_slice(&s.texels),
    },
    Table {
        what: "texel decoding table",
        texture: "texel_lut_tex",
        loader: "load_texel_lut",
        element: || Element::F32,
        bytes: |s| bytemuck::cast_slice(&s.texel_lut),
    },
    Table {
        what: "lights",
        texture: "lights_tex",
        loader: "load_light",
        element: || {
            Element::Struct(struct_layout!(Light {
                position,
                kind,
                direction,
                cos_cutoff,
                intensity,
                cos_beam,
                cutoff,
                inv_transition,
                shadows,
                area,
                edge,
                pmf,
            }))
        },
        bytes: |s| bytemuck::cast_slice(&s.lights),
    },
    Table {
        what: "emitters",
        texture: "emitters_tex",
        loader: "load_emitter",
        element: || Element::U32,
        bytes: |s| bytemuck::cast_slice(&s.emitters),
    },
    Table {
        what: "emitter CDF",
        texture: "emitter_cdf_tex",
        loader: "load_emitter_cdf",
        element: || Element::F32,
        bytes: |s| bytemuck::cast_slice(&s.emitter_cdf),
    },
    Table {
        what: "environment CDF",
        texture: "env_cdf_tex",
        loader: "load_env_cdf",
        element: || Element::F32,
        bytes: |s| bytemuck::cast_slice(&s.env_cdf),
    },
    Table {
        what: "caustic targets",
        texture: "caustic_targets_tex",
        loader: "load_caustic_target",
        element: || Element::Struct(struct_layout!(CausticTarget { center, radius })),
        bytes: |s| bytemuck::cast_slice(&s.caustic_targets),
    },
];

/// The element of both texture-coordinate tables, which share `TriUvs`.
fn tri_uvs_element() -> Element {
    Element::Struct(struct_layout!(TriUvs {
        uv0,
        uv1,
        uv2,
        _pad
    }))
}

/// The binding of the TLAS of hardware ray queries in the scene group, after the tables.
pub const TLAS_BINDING: u32 = TABLES.len() as u32 + 1;

/// The WGSL declaration of the TLAS (`scene_tlas`, read by `shaders/ray_query.wgsl`).
pub fn wgsl_tlas() -> String {
    format!("@group(0) @binding({TLAS_BINDING}) var scene_tlas: acceleration_structure;\n")
}

/// The WGSL bindings of the tables and their loaders: `fn load_node(i: u32) -> BvhNode`
/// reads element `i` of table `nodes_tex` through `table_texel` (`shaders/bindings.wgsl`),
/// member by member from the texel and component its Rust offset names.
pub fn wgsl_tables() -> String {
    let mut out = String::new();
    for (i, t) in TABLES.iter().enumerate() {
        out += &format!(
            "@group(0) @binding({}) var {}: texture_2d<u32>;\n",
            i + 1,
            t.texture
        );
    }
    for t in TABLES {
        out += &match (t.element)() {
            Element::U32 => format!(
                "\nfn {}(k: u32) -> u32 {{\n    return table_texel({}, k >> 2u)[k & 3u];\n}}\n",
                t.loader, t.texture
            ),
            Element::F32 => format!(
                "\nfn {}(k: u32) -> f32 {{\n    return bitcast<f32>(table_texel({}, k >> 2u)[k & 3u]);\n}}\n",
                t.loader, t.texture
            ),
            Element::Struct(layout) => struct_loader(t, &layout),
        };
    }
    out
}

/// The loader of a table of structs: the texels it needs, then the struct built from them
/// in member order.
fn struct_loader(t: &Table, layout: &StructLayout) -> String {
    assert!(
        layout.size.is_multiple_of(16),
        "{}: not whole texels",
        layout.name
    );
    let texels = layout.size / 16;
    let mut members: Vec<&Member> = layout.members.iter().collect();
    members.sort_by_key(|m| m.offset);
    let mut used = vec![false; texels];
    let args: Vec<String> = members
        .iter()
        .map(|m| {
            if m.wgsl == "padding" {
                // An array of padding words is that many `u32` members in WGSL.
                return vec!["0u"; m.size / 4].join(", ");
            }
            let (texel, first) = (m.offset / 16, m.offset % 16 / 4);
            let words = m.size / 4;
            assert!(
                first + words <= 4,
                "{}.{} straddles two texels",
                layout.name,
                m.name
            );
            used[texel] = true;
            let words = match words {
                4 => format!("t{texel}"),
                _ => format!("t{texel}.{}", &"xyzw"[first..first + words]),
            };
            match m.wgsl {
                "u32" => words,
                ty => format!("bitcast<{ty}>({words})"),
            }
        })
        .collect();
    let mut body = String::new();
    for (k, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        body += &format!(
            "    let t{k} = table_texel({}, {texels}u * i + {k}u);\n",
            t.texture
        );
    }
    format!(
        "\nfn {}(i: u32) -> {} {{\n{body}    return {}({});\n}}\n",
        t.loader,
        layout.name,
        layout.name,
        args.join(", ")
    )
}

/// The layout of the scene bind group (group 0): a parameter block, every table, and on a
/// device that traces with ray queries the TLAS. The same for every scene on a device, so
/// [`GpuDevice`](super::GpuDevice) makes it once and its pipelines serve every scene.
pub fn scene_layout(device: &wgpu::Device, ray_query: bool) -> wgpu::BindGroupLayout {
    let mut entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<Params>() as u64),
        },
        count: None,
    }];
    entries.extend(
        (1..=TABLES.len() as u32).map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        }),
    );
    if ray_query {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: TLAS_BINDING,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::AccelerationStructure {
                vertex_return: false,
            },
            count: None,
        });
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &entries,
    })
}
