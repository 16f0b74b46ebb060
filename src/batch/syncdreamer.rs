//! SyncDreamer's `meta.pkl`, which its script writes beside an object's random-elevation
//! views (`--camera_type random`): a Python pickle of the list
//! `[K, azimuths, elevations, distances, cam_poses]` of NumPy arrays, as
//! `save_pickle` writes it and SyncDreamer's data loader reads it.
//!
//! The pickle is written here (protocol 3) with the opcodes NumPy's own arrays reduce to:
//! `numpy.core.multiarray._reconstruct` and `numpy.dtype`, which NumPy 1.x and 2.x both load.

use super::preset::{Normalisation, Preset};

/// The bytes of `meta.pkl` for object `uid`, which `norm` normalises, under `preset`, in
/// images `width` × `height`:
/// - `K`: the 3 × 3 intrinsics in float32, f = width / (2 tan(fov / 2)) on both axes (the
///   script's `get_calibration_matrix_K_from_blender` takes the width's scale for both) and
///   the principal point at the image's centre;
/// - `azimuths` (float32) and `elevations` (float64), in radians ([`Preset::ring_angles`]);
/// - `distances` (float64): the preset's distance for every view;
/// - `cam_poses` (N × 3 × 4, float64): each view's world→camera [R | t] in OpenCV's
///   convention (x right, y down, z forward): Blender's pose ([`Preset::pose`]) with its
///   second and third rows negated, the script's `cam_rec`.
pub fn meta_pkl(
    preset: &Preset,
    uid: &str,
    norm: &Normalisation,
    (width, height): (u32, u32),
) -> Vec<u8> {
    let n = preset.views as usize;
    let f = width as f64 / 2.0 / (preset.fov as f64 / 2.0).to_radians().tan();
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let k = [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0].map(|v| v as f32);
    let (azimuths, elevations): (Vec<f32>, Vec<f64>) = (0..preset.views)
        .map(|v| preset.ring_angles(uid, v))
        .unzip();
    let distances = vec![preset.distance as f64; n];
    let poses: Vec<f64> = (0..preset.views)
        .flat_map(|v| {
            let [r, u, b] = preset.pose(uid, v, norm);
            [r, u.map(|x| -x), b.map(|x| -x)].into_iter().flatten()
        })
        .collect();
    let mut out = Pickle(vec![PROTO, 3]);
    out.0.push(EMPTY_LIST);
    out.0.push(MARK);
    out.array(&[3, 3], "f4", &le_bytes(&k, f32::to_le_bytes));
    out.array(&[n], "f4", &le_bytes(&azimuths, f32::to_le_bytes));
    out.array(&[n], "f8", &le_bytes(&elevations, f64::to_le_bytes));
    out.array(&[n], "f8", &le_bytes(&distances, f64::to_le_bytes));
    out.array(&[n, 3, 4], "f8", &le_bytes(&poses, f64::to_le_bytes));
    out.0.extend([APPENDS, STOP]);
    out.0
}

/// `values` as an array's data: each one's little-endian bytes, in order.
fn le_bytes<T: Copy, const N: usize>(values: &[T], bytes: fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| bytes(v)).collect()
}

const PROTO: u8 = 0x80;
const MARK: u8 = b'(';
const STOP: u8 = b'.';
const EMPTY_LIST: u8 = b']';
const APPENDS: u8 = b'e';
const GLOBAL: u8 = b'c';
const REDUCE: u8 = b'R';
const BUILD: u8 = b'b';
const TUPLE: u8 = b't';
const BININT: u8 = b'J';
const BINUNICODE: u8 = b'X';
const BINBYTES: u8 = b'B';
const NONE: u8 = b'N';
const NEWTRUE: u8 = 0x88;
const NEWFALSE: u8 = 0x89;

/// A pickle being written: its opcodes' bytes.
struct Pickle(Vec<u8>);

impl Pickle {
    fn global(&mut self, module: &str, name: &str) {
        self.0.push(GLOBAL);
        self.0.extend(format!("{module}\n{name}\n").bytes());
    }

    fn int(&mut self, v: i32) {
        self.0.push(BININT);
        self.0.extend(v.to_le_bytes());
    }

    fn text(&mut self, s: &str) {
        self.0.push(BINUNICODE);
        self.0.extend((s.len() as u32).to_le_bytes());
        self.0.extend(s.bytes());
    }

    fn bytes(&mut self, b: &[u8]) {
        self.0.push(BINBYTES);
        self.0.extend((b.len() as u32).to_le_bytes());
        self.0.extend(b);
    }

    /// A little-endian C-ordered array of `shape` and dtype `kind` (`f4`, `f8`) holding
    /// `data`, as `ndarray.__reduce__` gives it: `_reconstruct(ndarray, (0,), b'b')`, then
    /// the state `(1, shape, dtype, False, data)`.
    fn array(&mut self, shape: &[usize], kind: &str, data: &[u8]) {
        self.global("numpy.core.multiarray", "_reconstruct");
        self.0.push(MARK);
        self.global("numpy", "ndarray");
        self.0.push(MARK);
        self.int(0);
        self.0.push(TUPLE);
        self.bytes(b"b");
        self.0.extend([TUPLE, REDUCE]);
        self.0.push(MARK);
        self.int(1);
        self.0.push(MARK);
        for &d in shape {
            self.int(d as i32);
        }
        self.0.push(TUPLE);
        self.dtype(kind);
        self.0.push(NEWFALSE);
        self.bytes(data);
        self.0.extend([TUPLE, BUILD]);
    }

    /// `numpy.dtype(kind, False, True)` with the state of a little-endian number,
    /// `(3, '<', None, None, None, -1, -1, 0)`.
    fn dtype(&mut self, kind: &str) {
        self.global("numpy", "dtype");
        self.0.push(MARK);
        self.text(kind);
        self.0.extend([NEWFALSE, NEWTRUE, TUPLE, REDUCE]);
        self.0.push(MARK);
        self.int(3);
        self.text("<");
        self.0.extend([NONE, NONE, NONE]);
        self.int(-1);
        self.int(-1);
        self.int(0);
        self.0.extend([TUPLE, BUILD]);
    }
}
