//! Tangents for normal maps where the file gives none, as MikkTSpace computes them (the
//! convention glTF prescribes and Blender, Substance and xNormal bake with), through the
//! `bevy_mikktspace` crate: a safe port that gives the reference implementation's bits.

use super::material::Material;
use super::{Mesh, NO_NORMAL, NO_TANGENT, NO_TEXTURE, NO_UV, Texture};
use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};
use glam::{Vec3, Vec4};

/// The triangles of a mesh that need tangents, seen as MikkTSpace reads a mesh. Texture
/// coordinates are handed over with v negated: the mesh's run down the image, and the
/// normal maps' green channel points up it (OpenGL's convention, glTF's), so the
/// bitangent must follow decreasing v.
struct Faces<'a> {
    mesh: &'a Mesh,
    faces: Vec<u32>,
    /// Per face, its corners' texture coordinates in the set its normal map reads.
    uvs: Vec<[u32; 3]>,
    /// Per face corner: the tangent found, if any.
    out: Vec<Option<Vec4>>,
}

impl Faces<'_> {
    fn corner(&self, face: usize, vert: usize) -> (usize, usize) {
        (self.faces[face] as usize, vert)
    }
}

impl Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.faces.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        let (t, k) = self.corner(face, vert);
        let tri = &self.mesh.triangles[t];
        self.mesh.positions[tri.p[k] as usize].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let (t, k) = self.corner(face, vert);
        let tri = &self.mesh.triangles[t];
        if tri.n[0] != NO_NORMAL {
            return self.mesh.normals[tri.n[k] as usize].to_array();
        }
        let [a, b, c] = self.mesh.vertices(tri);
        (b - a).cross(c - a).normalize_or_zero().to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.mesh.texcoords[self.uvs[face][vert] as usize];
        [uv.x, -uv.y]
    }

    fn set_tangent(&mut self, tangent: Option<TangentSpace>, face: usize, vert: usize) {
        self.out[3 * face + vert] = tangent
            .map(|s| Vec4::from_array(s.tangent_encoded()))
            .filter(|t| t.truncate().is_finite() && t.truncate() != Vec3::ZERO);
    }
}

/// Gives MikkTSpace tangents to every triangle whose material has a normal map and whose
/// file gave none, from the texture coordinate set the map reads (`textures`, the texture
/// records, say which). Returns how many such triangles got none (MikkTSpace finds no tangent
/// for a triangle whose texture coordinates collapse and which has no neighbour to borrow
/// one from); their normal maps are not applied.
pub fn generate_missing(mesh: &mut Mesh, materials: &[Material], textures: &[Texture]) -> usize {
    let mut faces = Vec::new();
    let mut uvs = Vec::new();
    for (i, t) in mesh.triangles.iter().enumerate() {
        let map = materials[t.material as usize].tangent_map();
        if map == NO_TEXTURE || mesh.tangent_indices(i)[0] != NO_TANGENT {
            continue;
        }
        let corners = if textures[map as usize].uv_set == 1 {
            mesh.uv1_indices(i)
        } else {
            t.t
        };
        if corners[0] != NO_UV {
            faces.push(i as u32);
            uvs.push(corners);
        }
    }
    if faces.is_empty() {
        return 0;
    }
    let mut geometry = Faces {
        mesh,
        out: vec![None; 3 * faces.len()],
        faces,
        uvs,
    };
    // The crate's error type has no values yet; a corner it leaves without a tangent is
    // counted below either way.
    let _ = generate_tangents(&mut geometry);
    let Faces { faces, out, .. } = geometry;
    let mut missing = 0;
    mesh.tangent_corners
        .resize(mesh.triangles.len(), [NO_TANGENT; 3]);
    for (f, &t) in faces.iter().enumerate() {
        let corners = [out[3 * f], out[3 * f + 1], out[3 * f + 2]];
        let [Some(a), Some(b), Some(c)] = corners else {
            missing += 1;
            continue;
        };
        let base = mesh.tangents.len() as u32;
        mesh.tangents.extend([a, b, c]);
        mesh.tangent_corners[t as usize] = [base, base + 1, base + 2];
    }
    missing
}
