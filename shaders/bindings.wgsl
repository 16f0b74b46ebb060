// The scene, group 0: the tables of src/render/mod.rs `RenderScene`, uploaded as they are.
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> tris: array<TriVerts>;
@group(0) @binding(3) var<storage, read> shading: array<TriShading>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read> emitters: array<u32>;
@group(0) @binding(6) var<storage, read> emitter_cdf: array<f32>;
