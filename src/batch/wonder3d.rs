//! Wonder3D's camera rig and files (xxlong0/Wonder3D `render_codes/blenderProc_ortho.py`,
//! docs/dataset-scripts.md §6): thirteen named cameras on a rig of radius 2 about the
//! object, the whole rig turned at random per render, and per view an RGBA image whose
//! alpha is the object's mask, its camera-space normals with the same mask, and a
//! world→camera pose as text.

use crate::film::{Aov, AovValues, DisplayTransform, Film, NO_ID, quantise8};
use crate::scene::camera::Camera;
use glam::{DMat3, DVec3};

/// The rig's cameras in the script's order (`VIEWS + EXTRA_VIEWS`), with the directions
/// from the object to each in Blender's frame (front is −Y), before the rig turns.
pub const CAMERAS: [(&str, [f64; 3]); 13] = [
    ("front", [0.0, -1.0, 0.0]),
    ("back", [0.0, 1.0, 0.0]),
    ("right", [1.0, 0.0, 0.0]),
    ("left", [-1.0, 0.0, 0.0]),
    ("front_right", [1.0, -1.0, 0.0]),
    ("front_left", [-1.0, -1.0, 0.0]),
    ("back_right", [1.0, 1.0, 0.0]),
    ("back_left", [-1.0, 1.0, 0.0]),
    ("top", [0.0, 0.0, 1.0]),
    ("front_right_top", [1.0, -1.0, 1.0]),
    ("front_left_top", [-1.0, -1.0, 1.0]),
    ("back_right_top", [1.0, 1.0, 1.0]),
    ("back_left_top", [-1.0, 1.0, 1.0]),
];

/// The rig render and the camera of view `view`: views 0–12 are the cameras of render 0
/// (the script's `--view 0`), 13–25 those of render 1, and so on.
pub fn split(view: u32) -> (u32, usize) {
    (view / CAMERAS.len() as u32, view as usize % CAMERAS.len())
}

/// The script's name of view `view`: `f"{viewidx:03d}" + VIEWS[j]`, as in `000_front`.
pub fn view_name(view: u32) -> String {
    let (rig, camera) = split(view);
    format!("{rig:03}_{}", CAMERAS[camera].0)
}

/// The dimensions of the rig's two random angles ([`super::preset::uniform`]).
const TURN_Z: u32 = 1 << 20;
const TURN_X: u32 = TURN_Z + 1;

/// The turn of rig render `rig` of object `uid`: with `random` (the batch script's
/// `--random_pose`), δz uniform in [−60°, 60°] and δx in [−15°, 30°], which the script's
/// `transform.rotate` calls apply about the global axes with their signs turned, so the
/// rig turns by Rx(−δx) Rz(−δz); without, none.
pub fn turn(uid: &str, rig: u32, random: bool) -> DMat3 {
    if !random {
        return DMat3::IDENTITY;
    }
    let delta_z = -60.0 + 120.0 * crate::math::uniform(uid, rig, TURN_Z);
    let delta_x = -15.0 + 45.0 * crate::math::uniform(uid, rig, TURN_X);
    DMat3::from_rotation_x(-f64::to_radians(delta_x))
        * DMat3::from_rotation_z(-f64::to_radians(delta_z))
}

/// Camera `camera`'s rows right, up and back in the rig's own frame: its TRACK_TO
/// constraint (−Z at the rig's centre, +Y towards the rig's +Z, in its local space) gives
/// right = normalize(+Z × back), up = back × right; for `top`, where +Z is the view
/// direction, Blender's fallback gives right = +X and up = +Y.
pub fn local_axes(camera: usize) -> [DVec3; 3] {
    let back = DVec3::from(CAMERAS[camera].1).normalize();
    let right = DVec3::Z.cross(back).try_normalize().unwrap_or(DVec3::X);
    [right, back.cross(right), back]
}

/// Writes `rows` as NumPy's `np.savetxt` does with its default format: each value as
/// `%.18e`, separated by spaces, a row a line.
pub fn savetxt(path: &std::path::Path, rows: &[Vec<f64>]) -> Result<(), crate::film::FilmError> {
    crate::film::write_bytes(path, savetxt_text(rows).as_bytes())
}

/// The text [`savetxt`] writes.
pub fn savetxt_text(rows: &[Vec<f64>]) -> String {
    rows.iter()
        .map(|row| {
            let cells: Vec<String> = row.iter().map(|&x| percent_e(x)).collect();
            cells.join(" ") + "\n"
        })
        .collect()
}

/// `x` as C's `%.18e`: 18 digits after the point and a signed exponent of at least two
/// digits (Rust's `{:.18e}` writes `1.5e0`, C `1.5…e+00`).
fn percent_e(x: f64) -> String {
    let s = format!("{x:.18e}");
    match s.split_once('e') {
        Some((mantissa, exp)) => {
            let (sign, digits) = match exp.strip_prefix('-') {
                Some(d) => ('-', d),
                None => ('+', exp),
            };
            format!("{mantissa}e{sign}{digits:0>2}")
        }
        None => s,
    }
}

/// The two images the script writes of a view, 8-bit RGBA, from `film` (rendered through
/// `camera` with the [`Aov::Normal`] and [`Aov::ObjectId`] AOVs):
/// - the colour, formed by `view`, with alpha 255 where the pixel's centre ray hits the object
///   and 0 elsewhere (the script's mask: its unfiltered depth short of the background's);
/// - the normals in the camera's frame, Blender's convention (+X right, +Y up, +Z towards
///   the viewer), as Wonder3D stores them: ⌊255 (n + 1) / 2⌋, a miss counting n = 0
///   (127), with the same alpha.
pub fn images(
    film: &Film,
    camera: &Camera,
    view: &DisplayTransform,
) -> Result<(Vec<u8>, Vec<u8>), String> {
    let mask = match film.aov_values(Aov::ObjectId).as_deref() {
        Some([AovValues::U32(ids)]) => ids.iter().map(|&id| id != NO_ID).collect::<Vec<_>>(),
        _ => return Err("the render has no object_id AOV for the mask".into()),
    };
    let normal_values = film.aov_values(Aov::Normal);
    let normal = match normal_values.as_deref() {
        Some([AovValues::F32(x), AovValues::F32(y), AovValues::F32(z)]) => (x, y, z),
        _ => return Err("the render has no normal AOV".into()),
    };
    let alpha = |hit: bool| if hit { 255 } else { 0 };
    let rgb = film
        .mean()
        .iter()
        .zip(&mask)
        .flat_map(|(c, &hit)| {
            let [r, g, b] = view.encode(*c).map(quantise8);
            [r, g, b, alpha(hit)]
        })
        .collect();
    let encode = |v: f32| (255.0 * (v + 1.0) / 2.0).clamp(0.0, 255.0) as u8;
    let normals = (0..mask.len())
        .flat_map(|i| {
            let n = glam::Vec3::new(normal.0[i], normal.1[i], normal.2[i]);
            [
                encode(n.dot(camera.right)),
                encode(n.dot(camera.up)),
                encode(-n.dot(camera.forward)),
                alpha(mask[i]),
            ]
        })
        .collect();
    Ok((rgb, normals))
}

/// Writes an 8-bit RGBA image of `width` × `height` in the format `path`'s extension
/// names (PNG or lossless WebP), complete or not at all.
pub fn write_rgba(
    path: &std::path::Path,
    width: u32,
    height: u32,
    rgba: Vec<u8>,
) -> Result<(), crate::film::FilmError> {
    let format = image::ImageFormat::from_path(path).map_err(|e| crate::film::FilmError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    let io = |message: String| crate::film::FilmError::Io {
        path: path.display().to_string(),
        message,
    };
    let img =
        image::RgbaImage::from_raw(width, height, rgba).ok_or(io("image size mismatch".into()))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgba8(img)
        .write_to(&mut bytes, format)
        .map_err(|e| io(e.to_string()))?;
    crate::film::write_bytes(path, &bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_e_is_numpys() {
        // Each as Python writes `"%.18e" % x`.
        assert_eq!(percent_e(1.0), "1.000000000000000000e+00");
        assert_eq!(percent_e(-1.3), "-1.300000000000000044e+00");
        assert_eq!(percent_e(1.5e-7), "1.499999999999999932e-07");
        assert_eq!(percent_e(0.0), "0.000000000000000000e+00");
        assert_eq!(percent_e(2.5e123), "2.499999999999999871e+123");
    }

    #[test]
    fn names_follow_the_script() {
        assert_eq!(view_name(0), "000_front");
        assert_eq!(view_name(8), "000_top");
        assert_eq!(view_name(12), "000_back_left_top");
        assert_eq!(view_name(13), "001_front");
    }

    #[test]
    fn top_has_the_fallback_frame() {
        // Blender gives the unturned rig's top camera R = I (docs/dataset-scripts.md §6).
        assert_eq!(local_axes(8), [DVec3::X, DVec3::Y, DVec3::Z]);
    }
}
