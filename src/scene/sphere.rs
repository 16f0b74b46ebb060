//! Spheres, tessellated as subdivided icosahedra with normals from the centre.

use glam::Vec3;
use std::collections::HashMap;

/// The subdivision level at which the largest gap between a flat triangle and the true
/// sphere falls below 1/1000 of the radius (the spec's default), measured on the mesh.
pub fn default_subdivisions() -> u32 {
    (0..)
        .find(|&level| max_deviation(level) < 1e-3)
        .unwrap_or(0)
}

/// The largest distance, relative to the radius, between the unit sphere and the
/// triangles of `icosphere(level)`; a flat triangle is farthest from it at its centroid
/// (its closest point to the centre).
fn max_deviation(level: u32) -> f32 {
    let (v, f) = icosphere(level);
    f.iter()
        .map(|t| 1.0 - ((v[t[0] as usize] + v[t[1] as usize] + v[t[2] as usize]) / 3.0).length())
        .fold(0.0, f32::max)
}

/// Unit-sphere vertices and triangles (counter-clockwise seen from outside) at `level`.
pub fn icosphere(level: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&v| Vec3::from(v).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((verts[a as usize] + verts[b as usize]).normalize());
                verts.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = mid(a, b, &mut verts);
            let bc = mid(b, c, &mut verts);
            let ca = mid(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    (verts, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_level_meets_the_error_bound() {
        let level = default_subdivisions();
        let (v, f) = icosphere(level);
        // The worst point of a flat triangle is near its centroid.
        let worst = f
            .iter()
            .map(|t| {
                1.0 - ((v[t[0] as usize] + v[t[1] as usize] + v[t[2] as usize]) / 3.0).length()
            })
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "level {level}: deviation {worst}");
        let (v, f) = icosphere(level - 1);
        let coarser = f
            .iter()
            .map(|t| {
                1.0 - ((v[t[0] as usize] + v[t[1] as usize] + v[t[2] as usize]) / 3.0).length()
            })
            .fold(0.0f32, f32::max);
        assert!(coarser >= 1e-3, "level {} would do: {coarser}", level - 1);
    }

    #[test]
    fn faces_wind_outwards() {
        let (v, f) = icosphere(2);
        assert_eq!(f.len(), 20 * 16);
        for t in &f {
            let [a, b, c] = t.map(|i| v[i as usize]);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
        }
    }
}
