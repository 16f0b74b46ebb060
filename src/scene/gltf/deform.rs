//! What bends a primitive at its static pose, as glTF 2.0 defines it: morph targets
//! (weighted POSITION, NORMAL and TANGENT deltas, §3.7.2.2) applied first, then a skin
//! (§3.7.3): each vertex moved by the blend of its joints' matrices, a joint's matrix
//! being the joint node's global transform times its inverse bind matrix. Animations are
//! not played: the pose is the nodes' own transforms and the default weights.

use super::accessor::{self, Expect, read_floats};
use super::buffers::Buffers;
use super::draco::Source;
use crate::scene::SceneError;
use crate::scene::part::MeshPart;
use glam::{Mat3, Mat4, Vec3, Vec4};
use gltf::json::accessor::{ComponentType as C, Type};
use gltf::json::mesh::{Primitive, Semantic};

/// A primitive's morph targets and skin attributes, read once with its mesh and applied to
/// each node's copy.
#[derive(Debug, Default)]
pub(super) struct Deform {
    /// The morph targets, in order: each attribute's per-vertex delta, empty where the
    /// target does not move that attribute.
    targets: Vec<Target>,
    /// Per vertex, its joints (indices into the skin's `joints`) and their weights, four
    /// for each of JOINTS_0/WEIGHTS_0, JOINTS_1/WEIGHTS_1, … that the primitive has.
    joints: Vec<Vec<[u32; 4]>>,
    weights: Vec<Vec<[f32; 4]>>,
}

#[derive(Debug, Default)]
struct Target {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    tangents: Vec<Vec3>,
}

/// Joint indices: unsigned bytes or shorts, as integers.
const JOINTS: Expect = Expect {
    name: "JOINTS_n",
    ty: Type::Vec4,
    components: &[(C::U8, false), (C::U16, false)],
};

/// Joint weights: floats, or normalized unsigned bytes or shorts.
const WEIGHTS: Expect = Expect {
    name: "WEIGHTS_n",
    ty: Type::Vec4,
    components: &[(C::F32, false), (C::U8, true), (C::U16, true)],
};

/// Inverse bind matrices: column-major 4×4 floats.
const INVERSE_BIND_MATRICES: Expect = Expect {
    name: "inverseBindMatrices",
    ty: Type::Mat4,
    components: &[(C::F32, false)],
};

impl Deform {
    /// Reads primitive `primitive`'s morph targets and skin attributes (from `source`,
    /// its accessors or Draco stream); `n` is its vertex count and `at` its JSON path.
    pub fn read(
        source: &Source,
        primitive: &Primitive,
        at: &str,
        n: usize,
        quantized: bool,
    ) -> Result<Self, SceneError> {
        let buffers = source.buffers();
        let doc = buffers.doc();
        let vectors = |index: usize, at: String, expect: &Expect| {
            let values = read_floats(buffers, index, &at, expect)?;
            let v: Vec<Vec3> = values.chunks_exact(3).map(Vec3::from_slice).collect();
            if v.len() != n {
                return Err(doc.error(
                    at,
                    format!(
                        "accessor {index} has {} elements, but POSITION has {n}",
                        v.len()
                    ),
                ));
            }
            if let Some((i, d)) = v.iter().enumerate().find(|(_, d)| !d.is_finite()) {
                return Err(doc.error(
                    at,
                    format!("accessor {index}: delta {i} is not finite: {d}"),
                ));
            }
            Ok(v)
        };
        let mut deform = Deform::default();
        for (t, target) in primitive.targets.iter().flatten().enumerate() {
            let at = |name: &str| format!("{at}.targets[{t}].{name}");
            let read = |index: Option<gltf::json::Index<_>>, name: &str, expect: Expect| {
                index.map_or(Ok(Vec::new()), |i| vectors(i.value(), at(name), &expect))
            };
            deform.targets.push(Target {
                positions: read(target.positions, "POSITION", accessor::delta(quantized))?,
                normals: read(target.normals, "NORMAL", accessor::normal_delta(quantized))?,
                tangents: read(
                    target.tangents,
                    "TANGENT",
                    accessor::normal_delta(quantized),
                )?,
            });
        }
        for set in 0.. {
            let (Some(j), Some(w)) = (
                source.has(Semantic::Joints(set)),
                source.has(Semantic::Weights(set)),
            ) else {
                break;
            };
            let at_j = source.attribute_at(&format!("JOINTS_{set}"));
            let at_w = source.attribute_at(&format!("WEIGHTS_{set}"));
            let joints = source
                .floats(Semantic::Joints(set), &JOINTS)?
                .unwrap_or_default();
            let weights = source
                .floats(Semantic::Weights(set), &WEIGHTS)?
                .unwrap_or_default();
            for (values, index, at) in [(&joints, j, &at_j), (&weights, w, &at_w)] {
                if values.len() != 4 * n {
                    return Err(doc.error(
                        at,
                        format!(
                            "accessor {index} has {} elements, but POSITION has {n}",
                            values.len() / 4
                        ),
                    ));
                }
            }
            if let Some((i, x)) = weights
                .iter()
                .enumerate()
                .find(|(_, x)| !(x.is_finite() && **x >= 0.0))
            {
                return Err(doc.error(
                    at_w,
                    format!(
                        "accessor {w}: vertex {} has weight {x}; weights must be finite and at least 0",
                        i / 4
                    ),
                ));
            }
            let quads = |v: &[f32]| -> Vec<[f32; 4]> {
                v.chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], c[3]])
                    .collect()
            };
            deform.joints.push(
                quads(&joints)
                    .into_iter()
                    .map(|q| q.map(|j| j as u32))
                    .collect(),
            );
            deform.weights.push(quads(&weights));
        }
        Ok(deform)
    }

    /// How many morph targets the primitive has.
    pub fn target_count(&self) -> usize {
        self.targets.len()
    }

    /// Whether the primitive has skin attributes.
    pub fn is_skinned(&self) -> bool {
        !self.joints.is_empty()
    }

    /// The largest joint index any vertex names, if any.
    pub fn max_joint(&self) -> Option<u32> {
        self.joints.iter().flatten().flatten().copied().max()
    }

    /// Adds each target's deltas, times its weight, to `part`'s attributes. Normals and
    /// tangents are renormalised; a tangent keeps its handedness (w).
    pub fn morph(&self, part: &mut MeshPart, weights: &[f32]) {
        for (target, &w) in self.targets.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            for (p, d) in part.positions.iter_mut().zip(&target.positions) {
                *p += w * *d;
            }
            for (n, d) in part.normals.iter_mut().zip(&target.normals) {
                *n += w * *d;
            }
            for (t, d) in part.tangents.iter_mut().zip(&target.tangents) {
                *t = (t.truncate() + w * *d).extend(t.w);
            }
        }
        if weights.iter().any(|&w| w != 0.0) {
            renormalise(part);
        }
    }

    /// Moves `part`'s vertices by the blend of `joints` (each joint's global transform
    /// times its inverse bind matrix) their weights give: positions by the blended matrix,
    /// normals by its inverse transpose, tangents by it. The result is in world space. A
    /// vertex whose weights sum to other than 1 has them scaled to sum to 1, and one whose
    /// weights are all zero follows its first joint, as three.js's loader does.
    pub fn skin(&self, part: &mut MeshPart, joints: &[Mat4]) {
        for v in 0..part.positions.len() {
            let mut influences = self
                .joints
                .iter()
                .zip(&self.weights)
                .flat_map(|(j, w)| j[v].into_iter().zip(w[v]));
            let total: f32 = self.weights.iter().map(|w| w[v].iter().sum::<f32>()).sum();
            let mut m = Mat4::ZERO;
            if total > 0.0 {
                for (j, w) in influences.by_ref() {
                    if w > 0.0 {
                        m += joints[j as usize] * (w / total);
                    }
                }
            } else if let Some((j, _)) = influences.next() {
                m = joints[j as usize];
            }
            part.positions[v] = m.transform_point3(part.positions[v]);
            let linear = Mat3::from_mat4(m);
            if let Some(n) = part.normals.get_mut(v) {
                let inverse_transpose = linear.inverse().transpose();
                let moved = inverse_transpose * *n;
                *n = if moved.is_finite() {
                    moved.normalize_or_zero()
                } else {
                    Vec3::ZERO
                };
            }
            if let Some(t) = part.tangents.get_mut(v) {
                let moved = (linear * t.truncate()).normalize_or_zero();
                *t = moved.extend(t.w);
            }
        }
    }
}

/// Unit normals and tangents again after deltas were added; one that became zero or not
/// finite is zero, which the scene builder reads as none.
fn renormalise(part: &mut MeshPart) {
    for n in &mut part.normals {
        *n = n.normalize_or_zero();
    }
    for t in &mut part.tangents {
        let xyz = t.truncate().normalize_or_zero();
        *t = if xyz == Vec3::ZERO {
            Vec4::ZERO
        } else {
            xyz.extend(t.w)
        };
    }
}

/// Skin `s`'s inverse bind matrices, one per joint (identity where the skin has none).
pub(super) fn inverse_bind_matrices(
    buffers: &Buffers,
    s: usize,
    skin: &gltf::json::Skin,
) -> Result<Vec<Mat4>, SceneError> {
    let doc = buffers.doc();
    let Some(index) = skin.inverse_bind_matrices else {
        return Ok(vec![Mat4::IDENTITY; skin.joints.len()]);
    };
    let at = format!("skins[{s}].inverseBindMatrices");
    let values = read_floats(buffers, index.value(), &at, &INVERSE_BIND_MATRICES)?;
    let matrices: Vec<Mat4> = values.chunks_exact(16).map(Mat4::from_cols_slice).collect();
    if matrices.len() < skin.joints.len() {
        return Err(doc.error(
            at,
            format!(
                "accessor {} has {} matrices, but the skin has {}",
                index.value(),
                matrices.len(),
                super::count(skin.joints.len(), "joint")
            ),
        ));
    }
    if matrices.iter().any(|m| !m.is_finite()) {
        return Err(doc.error(
            at,
            format!("accessor {}: a matrix is not finite", index.value()),
        ));
    }
    Ok(matrices)
}
