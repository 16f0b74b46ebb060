//! Dataset presets: a batch job that renders each mesh as a public dataset script does
//! (docs/dataset-scripts.md, docs/datasets.md): the script's normalisation of the object
//! into a unit box about the origin, its cameras, lens, lighting and image size, and its
//! files. Poses are the script's, in its own world frame: Blender's, Z up, which its glTF
//! and OBJ importers make of a Y-up file as (x, y, z) → (x, −z, y).
//!
//! Rather than move the mesh, the scene is left where the file puts it and the cameras
//! and lights are moved by the inverse of the normalisation: the images are the same.

use crate::math::{Aabb, uniform};
use crate::request::RenderRequest;
use crate::scene::camera::Camera;
use crate::scene::light::PunctualLight;
use crate::scene::studio::Up;
use crate::scene::texture::{ImageType, TextureError, TextureRef, TextureSource, Textures};
use crate::scene::{BounceLimits, Scene, SceneError, Sky};
use glam::{DVec3, Vec3};

use super::trellis::{Passes, depth_range};
use super::wonder3d;

/// The presets there are, by their manifest names.
pub const NAMES: [&str; 6] = [
    "objaverse",
    "objaverse-xl",
    "syncdreamer",
    "trellis",
    "wonder3d",
    "zero123",
];

/// Where a script puts its cameras.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Layout {
    /// Evenly spaced in azimuth on a ring at the preset's elevation and distance.
    Ring,
    /// SyncDreamer's `--camera_type random` (its input views): the ring's azimuths, each
    /// view at its own elevation, uniform in [`min`, `max`] degrees (the script's
    /// `--elevation_start` and `--elevation_end`), at the preset's distance.
    RandomRing { min: f32, max: f32 },
    /// Zero123's and Objaverse-XL's `sample_spherical`, drawn anew for each view: the
    /// direction of a point uniform in the cube [−1, 1]³ (not uniform on the sphere: it
    /// favours the cube's diagonals), at a distance uniform in [`radius_min`, `radius_max`];
    /// with `north_only`, the direction's z made positive (Objaverse-XL's
    /// `--only_northern_hemisphere`).
    Shell {
        radius_min: f32,
        radius_max: f32,
        north_only: bool,
    },
    /// TRELLIS's `sphere_hammersley_sequence` at the preset's distance: view i of n at
    /// u = i / n + o₀ / n, v = φ₂(i) + o₁ (φ₂ the base-2 radical inverse, o an offset drawn
    /// once per object), u' = 2u below 1/4 and 2u / 3 + 1/3 above (a quarter of the views
    /// below the horizon, three quarters above), pitch = acos(1 − 2u') − π/2, yaw = 2π v.
    Hammersley,
    /// Wonder3D's rig ([`wonder3d`]): thirteen named cameras at the preset's distance, view
    /// v being camera v mod 13 of rig render ⌊v / 13⌋, each render's rig turned at random
    /// when `random` (the script's `--random_pose`).
    Rig { random: bool },
}

impl Layout {
    /// Whether a manifest may set `key` (a camera parameter) for this layout.
    pub fn takes(&self, key: &str) -> bool {
        match self {
            Layout::Ring => matches!(key, "elevation" | "distance"),
            Layout::RandomRing { .. } => matches!(key, "elevation_range" | "distance"),
            Layout::Shell { .. } => matches!(key, "radius" | "only_northern_hemisphere"),
            Layout::Hammersley => key == "distance",
            Layout::Rig { .. } => matches!(key, "random_pose" | "ortho_scale"),
        }
    }

    /// The keys [`Layout::takes`], for messages.
    pub fn keys(&self) -> &'static str {
        match self {
            Layout::Ring => "elevation and distance",
            Layout::RandomRing { .. } => "elevation_range = [min, max] and distance",
            Layout::Shell { .. } => "radius = [min, max] and only_northern_hemisphere",
            Layout::Hammersley => "distance",
            Layout::Rig { .. } => "random_pose and ortho_scale",
        }
    }
}

/// How a script scales the object into its unit box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fit {
    /// The box's largest extent becomes 1 (all but Wonder3D's orthographic script).
    Extent,
    /// The box's diagonal becomes 1 (Wonder3D's `blenderProc_ortho.py`).
    Diagonal,
}

/// Where a script's cameras look.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    /// At the normalised object's centre, the origin.
    Centre,
    /// At the origin of the file's own frame, carried by the normalisation to −s c (c the
    /// original box's centre): Objaverse-XL's tracking target is created before it
    /// normalises and moves with the object, so an object whose box is not centred on its
    /// file's origin comes out off-centre, in the images and in their poses alike.
    FileOrigin,
}

/// The pose file a script writes beside each image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Poses {
    None,
    /// `{view:03}.npy`: the 3 × 4 world→camera matrix [R | t] in float32 (NumPy's array of
    /// Blender's single-precision `Matrix`, as the script saves it), in Blender's camera
    /// convention (looking down −Z, +Y up) and the normalised frame.
    Npy,
    /// TRELLIS's `transforms.json` per object ([`Preset::trellis_transforms`]).
    Transforms,
    /// Wonder3D's: per view `{name}_RT.txt`, the 3 × 4 world→camera [R | t] as `np.savetxt`
    /// writes Blender's single-precision matrix, in Blender's camera convention; per object
    /// `scale_offset_matrix.txt` (scale, offset and orthographic scale, a value a line);
    /// and per view, beside the colour, `normals_{name}` ([`wonder3d::images`]).
    RtTxt,
    /// SyncDreamer's `meta.pkl` per object ([`super::syncdreamer::meta_pkl`]): K, the azimuths,
    /// elevations and distances, and every view's world→camera pose in OpenCV's convention.
    MetaPkl,
}

/// How a script lights the object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lighting {
    /// objaverse-rendering's area light of 30,000 W, 100 m × 100 m, 0.5 over the object,
    /// with the factory world's grey (0.0509) below.
    AreaAbove,
    /// Blender's factory point light (1,000 W at (4.0762, 1.0055, 5.9039), moved with the
    /// object by the normalisation) in a uniform world of this grey.
    FactoryPoint { world: f32 },
    /// TRELLIS's, made after it normalises (so not scaled with the object): a point light of
    /// 1,000 W at (4, 1, 6), an area light 25 m wide of 10,000 W at (0, 0, 10) facing down
    /// (its bottom light faces away and lights nothing), the factory world's grey.
    Trellis,
    /// Objaverse-XL's: four suns without shadows, their strengths (W/m²) drawn once per
    /// object from Key {3, 4, 5}, Fill {2, 3, 4}, Rim {3, 4, 5}, Bottom {1, 2, 3}, travelling
    /// along (0.5, 0.5, −0.7071), (−0.5, −0.5, −0.7071), (0.5, 0.5, −0.7071) and (0, 0, 1);
    /// the factory world's grey.
    Suns,
    /// Zero123's: the factory point light, the factory world's grey (0.0509) and an area
    /// light drawn once per object: 300–600 W, 100 / scale wide (the normalisation scales
    /// it as a root object), at (U(−1, 1), U(−1, 1), U(0.5, 1.5)), facing down.
    Zero123,
    /// Wonder3D's orthographic script's: four suns without shadows, made before it
    /// normalises (directions only matter): 5 W/m² straight down, and three of 3 W/m²
    /// turned about X by 180, 90 and −90 *radians* (the script adds radians to Blender's
    /// Euler angles), travelling along (0, −0.8012, 0.5985), (0, 0.8940, 0.4481) and
    /// (0, −0.8940, 0.4481); a world of 0.4 grey at strength 0.5, which the camera sees.
    Wonder3d,
}

/// A dataset script's way of rendering, with the parameters a manifest may override.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// Its manifest name.
    pub name: &'static str,
    pub aim: Aim,
    pub fit: Fit,
    /// Whether it writes `metadata.json` beside each object's images.
    pub metadata: bool,
    /// Views per object.
    pub views: u32,
    pub layout: Layout,
    /// A ring's elevation above the object's horizontal plane, in degrees.
    pub elevation: f32,
    /// A ring's distance from the object's centre, in normalised units.
    pub distance: f32,
    /// The field of view of the square image, in degrees.
    pub fov: f32,
    /// An orthographic camera's view width and height in normalised units (Blender's
    /// `ortho_scale`); 0 for a perspective camera.
    pub ortho_scale: f32,
    /// The image's side in pixels.
    pub size: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// The script's `cycles.filter_width`: 0.01 pixels (every sample through the pixel's
    /// centre, no anti-aliasing) in all but TRELLIS's, which keeps 1.
    pub filter_width: f32,
    /// The script's longest path, from Cycles' `max_bounces` (segments: bounces + 2).
    pub max_depth: u32,
    /// The script's `diffuse_bounces`, `glossy_bounces` and `transmission_bounces`.
    pub bounces: BounceLimits,
    pub lighting: Lighting,
    pub poses: Poses,
    /// TRELLIS's `--save_depth`, `--save_normal`, `--save_albedo` and `--save_mist`: each
    /// view's passes beside its image ([`super::trellis`]).
    pub passes: Passes,
}

/// The light paths of the Zero123 script and those made from it (objaverse-rendering,
/// Objaverse-XL, SyncDreamer, TRELLIS): `diffuse_bounces = 1`, `glossy_bounces = 1`,
/// `transmission_bounces = 3` (and `transparent_max_bounces = 3`: meshtrace passes
/// alpha-masked surfaces without counting them).
const SCRIPT_BOUNCES: BounceLimits = BounceLimits {
    diffuse: Some(1),
    glossy: Some(1),
    transmission: Some(3),
};

/// The `max_depth` of Cycles' `max_bounces` of `bounces`: its kernel lets a path scatter
/// `bounces` + 1 times, and the segment after the last scattering still finds emission.
const fn cycles_max_depth(bounces: u32) -> u32 {
    bounces + 2
}

/// Blender's default `max_bounces`, which the scripts keep.
const BLENDER_MAX_BOUNCES: u32 = 12;

impl Preset {
    /// The preset named `name` with its script's parameters, or why there is none.
    pub fn named(name: &str) -> Result<Self, String> {
        match name {
            // allenai/objaverse-rendering scripts/blender_script.py: 12 views on a ring at
            // 30° elevation (polar angle 60°), distance 1.5, a 35 mm lens on a 32 mm
            // sensor, 512², RGBA PNG.
            "objaverse" => Ok(Self {
                name: "objaverse",
                aim: Aim::Centre,
                fit: Fit::Extent,
                metadata: false,
                layout: Layout::Ring,
                views: 12,
                elevation: 30.0,
                distance: 1.5,
                fov: fov_of_lens(35.0, 32.0),
                ortho_scale: 0.0,
                size: 512,
                spp: 64,
                filter_width: 0.01,
                max_depth: cycles_max_depth(BLENDER_MAX_BOUNCES),
                bounces: SCRIPT_BOUNCES,
                lighting: Lighting::AreaAbove,
                poses: Poses::None,
                passes: Passes::default(),
            }),
            // liuyuan-pal/SyncDreamer blender_script.py, --camera_type fixed (its target
            // views): 16 views on a ring at 30° elevation, distance 1.5, the same lens,
            // 256², no lights of its own (the factory point light stays) and a world of
            // grey 0.5.
            "syncdreamer" => Ok(Self {
                name: "syncdreamer",
                aim: Aim::Centre,
                fit: Fit::Extent,
                metadata: false,
                layout: Layout::Ring,
                views: 16,
                elevation: 30.0,
                distance: 1.5,
                fov: fov_of_lens(35.0, 32.0),
                ortho_scale: 0.0,
                size: 256,
                spp: 128,
                filter_width: 0.01,
                max_depth: cycles_max_depth(BLENDER_MAX_BOUNCES),
                bounces: SCRIPT_BOUNCES,
                lighting: Lighting::FactoryPoint { world: 0.5 },
                poses: Poses::None,
                passes: Passes::default(),
            }),
            // cvlab-columbia/zero123 objaverse-rendering/scripts/blender_script.py: views
            // at random on a shell of radius 1.5–2.2, the same lens, 512², 128 samples,
            // a `.npy` pose per view. 12 views, as the released data and its loader have
            // (the script's own default is 8).
            "zero123" => Ok(Self {
                name: "zero123",
                aim: Aim::Centre,
                fit: Fit::Extent,
                metadata: false,
                layout: Layout::Shell {
                    radius_min: 1.5,
                    radius_max: 2.2,
                    north_only: false,
                },
                views: 12,
                elevation: 0.0,
                distance: 0.0,
                fov: fov_of_lens(35.0, 32.0),
                ortho_scale: 0.0,
                size: 512,
                spp: 128,
                filter_width: 0.01,
                max_depth: cycles_max_depth(BLENDER_MAX_BOUNCES),
                bounces: SCRIPT_BOUNCES,
                lighting: Lighting::Zero123,
                poses: Poses::Npy,
                passes: Passes::default(),
            }),
            // microsoft/TRELLIS dataset_toolkits/render.py and blender_script/render.py: 150
            // views on a Hammersley sphere of radius 2, a 40° field of view, 512², 128
            // samples, transforms.json.
            "trellis" => Ok(Self {
                name: "trellis",
                aim: Aim::Centre,
                fit: Fit::Extent,
                metadata: false,
                layout: Layout::Hammersley,
                views: 150,
                elevation: 0.0,
                distance: 2.0,
                fov: 40.0,
                ortho_scale: 0.0,
                size: 512,
                spp: 128,
                filter_width: 1.0,
                max_depth: cycles_max_depth(BLENDER_MAX_BOUNCES),
                bounces: SCRIPT_BOUNCES,
                lighting: Lighting::Trellis,
                poses: Poses::Transforms,
                passes: Passes::default(),
            }),
            // allenai/objaverse-xl scripts/rendering/blender_script.py: Zero123's shell of
            // cameras (looking at the file's origin), four shadowless suns, 512², a `.npy`
            // pose per view and `metadata.json`. The script renders with EEVEE.
            "objaverse-xl" => Ok(Self {
                name: "objaverse-xl",
                aim: Aim::FileOrigin,
                metadata: true,
                spp: 64,
                lighting: Lighting::Suns,
                ..Self::named("zero123")?
            }),
            // xxlong0/Wonder3D render_codes/blenderProc_ortho.py, as render_batch_ortho.sh
            // runs it (--ortho_scale 1.35 --random_pose): the thirteen cameras of a rig of
            // radius 2, orthographic, 1.35 wide, 512², the object's box diagonal scaled to
            // 1, four shadowless suns and a visible grey world; per view the colour and the
            // camera-space normals as WebP with the mask as alpha, and the pose as text.
            // Cycles' 1,024 samples are the script's cap, which its adaptive sampling
            // (threshold 0.01) stops short of in most pixels.
            "wonder3d" => Ok(Self {
                name: "wonder3d",
                aim: Aim::Centre,
                fit: Fit::Diagonal,
                metadata: false,
                layout: Layout::Rig { random: true },
                views: wonder3d::CAMERAS.len() as u32,
                elevation: 0.0,
                distance: 2.0,
                fov: fov_of_lens(35.0, 32.0),
                ortho_scale: 1.35,
                size: 512,
                spp: 1024,
                filter_width: 1.0,
                // BlenderProc 2.5's defaults (`bproc.init()`), which the script keeps:
                // `max_bounces = 3`, `diffuse_bounces = 3`, `glossy_bounces = 0`,
                // `transmission_bounces = 0`.
                max_depth: cycles_max_depth(3),
                bounces: BounceLimits {
                    diffuse: Some(3),
                    glossy: Some(0),
                    transmission: Some(0),
                },
                lighting: Lighting::Wonder3d,
                poses: Poses::RtTxt,
                passes: Passes::default(),
            }),
            _ => Err(format!(
                "`{name}` is not a preset; there are {}",
                NAMES.map(|n| format!("\"{n}\"")).join(", ")
            )),
        }
    }

    /// What the preset asks of every image, under the manifest's `[render]`: its size,
    /// samples and pixel filter, RGBA PNGs (the scripts' transparent film; Wonder3D's film
    /// is opaque and takes its mask and normals from [`Preset::aovs`]), no studio, and the
    /// mesh read with +Y up, as Blender's glTF and OBJ importers read it.
    pub fn request(&self) -> RenderRequest {
        let rig = self.rig();
        RenderRequest {
            up: Some(Up::Y),
            width: Some(self.size),
            height: Some(self.size),
            spp: Some(self.spp),
            filter_width: Some(self.filter_width),
            max_depth: Some(self.max_depth),
            diffuse_bounces: self.bounces.diffuse,
            glossy_bounces: self.bounces.glossy,
            transmission_bounces: self.bounces.transmission,
            transparent: Some(!rig),
            without_studio: true,
            ..RenderRequest::default()
        }
    }

    /// The AOVs the preset's files are made of, whatever else the manifest asks for.
    pub fn aovs(&self) -> Vec<crate::film::Aov> {
        if self.rig() {
            vec![crate::film::Aov::Normal, crate::film::Aov::ObjectId]
        } else {
            self.passes.aovs()
        }
    }

    /// The output pattern of the script's images: one folder per object (its file name up
    /// to the first dot), the views numbered with three digits, or Wonder3D's named ones
    /// in folders by the uid's first two characters. Pose files go beside them.
    pub fn output(&self) -> &'static str {
        match self.poses {
            Poses::Transforms => "renders/{uid}/{view:03}.png",
            Poses::RtTxt => "views/{uid:2}/{uid}/rgb_{name}.webp",
            Poses::None | Poses::Npy | Poses::MetaPkl => "views/{uid}/{view:03}.png",
        }
    }

    /// The script's name of view `view` where its views have names (Wonder3D's
    /// `000_front`; [`wonder3d::view_name`]).
    pub fn view_name(&self, view: u32) -> Option<String> {
        self.rig().then(|| wonder3d::view_name(view))
    }

    /// Whether the views are Wonder3D's rig ([`Layout::Rig`]): named views on an opaque
    /// film, whose mask and normals go into the script's own images rather than beside them.
    pub fn rig(&self) -> bool {
        matches!(self.layout, Layout::Rig { .. })
    }

    /// The script's normalisation of a mesh of bounds `b` ([`Fit`]); `None` for an empty
    /// or flat-less box.
    pub fn normalisation(&self, b: &Aabb) -> Option<Normalisation> {
        match self.fit {
            Fit::Extent => Normalisation::of(b),
            Fit::Diagonal => Normalisation::of_diagonal(b),
        }
    }

    /// The camera position of view `view` of object `uid` in the script's normalised frame
    /// (Blender's, Z up). On a ring: at the preset's elevation and distance, view 0 on +X,
    /// turning counter-clockwise seen from +Z; on a random ring, at the view's own elevation
    /// ([`Preset::ring_angles`]). On a shell: drawn as the layout says, from [`uniform`]
    /// numbers of the object and view.
    pub fn blender_position(&self, uid: &str, view: u32) -> DVec3 {
        match self.layout {
            Layout::Ring => {
                let theta = std::f64::consts::TAU * view as f64 / self.views as f64;
                let phi = (90.0 - self.elevation as f64).to_radians();
                self.distance as f64
                    * DVec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos())
            }
            Layout::RandomRing { .. } => {
                let (azimuth, elevation) = self.ring_angles(uid, view);
                let (a, e) = (azimuth as f64, elevation);
                self.distance as f64 * DVec3::new(a.cos() * e.cos(), a.sin() * e.cos(), e.sin())
            }
            Layout::Shell {
                radius_min,
                radius_max,
                north_only,
            } => {
                // np.random.uniform(-1, 1, 3), normalised; np.random.uniform(rmin, rmax).
                // A draw at the cube's centre (probability 0) would have no direction: the
                // next numbers are taken.
                let mut k = 0;
                let dir = loop {
                    let v = DVec3::new(
                        2.0 * uniform(uid, view, k) - 1.0,
                        2.0 * uniform(uid, view, k + 1) - 1.0,
                        2.0 * uniform(uid, view, k + 2) - 1.0,
                    );
                    if let Some(d) = v.try_normalize() {
                        break if north_only { d.with_z(d.z.abs()) } else { d };
                    }
                    k += 3;
                };
                let (lo, hi) = (radius_min as f64, radius_max as f64);
                dir * (lo + (hi - lo) * uniform(uid, view, SHELL_RADIUS))
            }
            Layout::Hammersley => {
                let n = self.views as f64;
                let (o0, o1) = (uniform(uid, OBJECT, 10), uniform(uid, OBJECT, 11));
                let u = view as f64 / n + o0 / n;
                let v = radical_inverse_2(view) + o1;
                let u = if u < 0.25 {
                    2.0 * u
                } else {
                    2.0 / 3.0 * u + 1.0 / 3.0
                };
                let pitch = (1.0 - 2.0 * u).acos() - std::f64::consts::FRAC_PI_2;
                let yaw = v * std::f64::consts::TAU;
                self.distance as f64
                    * DVec3::new(
                        yaw.cos() * pitch.cos(),
                        yaw.sin() * pitch.cos(),
                        pitch.sin(),
                    )
            }
            Layout::Rig { random } => {
                let (rig, camera) = wonder3d::split(view);
                let local = DVec3::from(wonder3d::CAMERAS[camera].1).normalize();
                wonder3d::turn(uid, rig, random) * (self.distance as f64 * local)
            }
        }
    }

    /// A random ring's azimuth and elevation of view `view` of object `uid`, in radians, as
    /// SyncDreamer's script holds them: the azimuth 2π view / views in single precision
    /// (its `astype(np.float32)`), the elevation `np.deg2rad(np.random.uniform(min, max))`
    /// in double, drawn from [`uniform`]. On another layout, its azimuth and elevation.
    pub fn ring_angles(&self, uid: &str, view: u32) -> (f32, f64) {
        let azimuth = (std::f64::consts::TAU * view as f64 / self.views as f64) as f32;
        let degrees = match self.layout {
            Layout::RandomRing { min, max } => {
                min as f64 + (max as f64 - min as f64) * uniform(uid, view, RING_ELEVATION)
            }
            _ => self.elevation as f64,
        };
        (azimuth, degrees.to_radians())
    }

    /// TRELLIS's `transforms.json` of object `uid`, which `norm` normalises: the unit box,
    /// the normalisation (`scale`, `offset` in Blender's frame), and per view its image, its
    /// horizontal field of view in radians and its camera→world matrix in Blender's camera
    /// convention (columns right, up, back and the position), as `get_transform_matrix`
    /// writes them; with the depth pass, the range its PNG maps to [0, 1].
    pub fn trellis_transforms(&self, uid: &str, norm: &Normalisation) -> serde_json::Value {
        let frames: Vec<serde_json::Value> = (0..self.views)
            .map(|view| {
                let [r, u, b] = self.pose(uid, view, norm);
                let c = self.blender_position(uid, view);
                let m: Vec<[f64; 4]> = (0..3)
                    .map(|k| [r[k], u[k], b[k], c[k]])
                    .chain([[0.0, 0.0, 0.0, 1.0]])
                    .collect();
                let mut frame = serde_json::json!({
                    "file_path": format!("{view:03}.png"),
                    "camera_angle_x": (self.fov as f64).to_radians(),
                    "transform_matrix": m,
                });
                if self.passes.depth {
                    let [min, max] = depth_range(self.distance as f64);
                    frame["depth"] = serde_json::json!({"min": min, "max": max});
                }
                frame
            })
            .collect();
        serde_json::json!({
            "aabb": [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]],
            "scale": norm.scale,
            "offset": norm.blender_offset().to_array(),
            "frames": frames,
        })
    }

    /// Where the cameras of an object that `norm` normalises look, in the script's
    /// normalised frame ([`Aim`]).
    pub fn blender_target(&self, norm: &Normalisation) -> DVec3 {
        match self.aim {
            Aim::Centre => DVec3::ZERO,
            Aim::FileOrigin => norm.blender_offset(),
        }
    }

    /// The world→camera pose [R | t] of view `view` of object `uid`, which `norm`
    /// normalises, as the script saves it: Blender's camera convention (looking down −Z, +Y
    /// up), in the normalised frame, from the camera's TRACK_TO constraint (−Z at the target
    /// T, +Y towards world +Z): rows right r = normalize(+Z × b), up u = b × r, back
    /// b = (C − T) / |C − T|; t = −R C.
    ///
    /// On Wonder3D's rig the constraint works in the rig's frame, so the axes are the
    /// rig's ([`wonder3d::local_axes`]) turned with it.
    pub fn pose(&self, uid: &str, view: u32, norm: &Normalisation) -> [[f64; 4]; 3] {
        let c = self.blender_position(uid, view);
        let [r, u, b] = match self.layout {
            Layout::Rig { random } => {
                let (rig, camera) = wonder3d::split(view);
                let turn = wonder3d::turn(uid, rig, random);
                wonder3d::local_axes(camera).map(|axis| turn * axis)
            }
            _ => {
                let b = (c - self.blender_target(norm)).normalize();
                let r = DVec3::Z.cross(b).try_normalize().unwrap_or(DVec3::X);
                [r, b.cross(r), b]
            }
        };
        let mut out = [[0.0; 4]; 3];
        for (row, axis) in out.iter_mut().zip([r, u, b]) {
            *row = [axis.x, axis.y, axis.z, -axis.dot(c)];
        }
        out
    }

    /// The camera of view `view` of object `uid`, a mesh that `norm` normalises, in the
    /// mesh's own frame: at the script's position, looking at the origin with Blender's +Z
    /// up (on Wonder3D's rig, the pose's up), both taken back through the normalisation;
    /// orthographic, `ortho_scale` normalised units across, where the preset says so.
    pub fn camera(&self, uid: &str, view: u32, norm: &Normalisation) -> Option<Camera> {
        let position = norm.to_scene(to_meshtrace(self.blender_position(uid, view)));
        let up = match self.layout {
            Layout::Rig { .. } => {
                let [_, u, _] = self.pose(uid, view, norm);
                to_meshtrace(DVec3::new(u[0], u[1], u[2]))
            }
            _ => Vec3::Y,
        };
        let camera = Camera::new(
            position,
            norm.to_scene(to_meshtrace(self.blender_target(norm))),
            up,
            self.fov,
            0.0,
            None,
        )?;
        Some(if self.ortho_scale > 0.0 {
            camera.orthographic(self.ortho_scale / norm.scale)
        } else {
            camera
        })
    }

    /// Lights `scene`, object `uid` normalised by `norm`, as the script does ([`Lighting`]).
    ///
    /// objaverse-rendering's area light emits 30,000 / (π · 100²) as Cycles emits a watt
    /// of an area light (P / (π A)). Seen from the object, below it, it fills the sky down
    /// to within a degree of the horizon, and in Blender it neither occludes nor is seen by
    /// the camera: so it is this environment, the light's radiance above the horizon and
    /// the world's grey below.
    ///
    /// The factory point light is a root object when the script normalises, so it moves
    /// with the object: in the mesh's own frame it stays at its Blender position divided
    /// by the scale, and its intensity, P / (4π) W/sr as Cycles emits a point light's
    /// watts, is divided by the scale squared, so that the object receives what it does in
    /// the script. (Blender's light is a sphere of radius 0.1 m, meshtrace's a point: the
    /// shadows are harder.)
    ///
    /// Zero123's area light is scaled with the object (it is a root object when the script
    /// normalises): 100 s wide in the normalised frame, which is 100 wide in the mesh's
    /// own, and its radiance, P / (π (100 s)²), depends on the object's original size. Like
    /// every Blender light in Cycles it is seen by no camera and shadows nothing: a
    /// meshtrace `rect` light.
    pub fn light(
        &self,
        scene: &mut Scene,
        norm: &Normalisation,
        uid: &str,
    ) -> Result<(), SceneError> {
        match self.lighting {
            Lighting::AreaAbove => {
                let side = 100.0f32;
                let radiance = 30_000.0 / (std::f32::consts::PI * side * side);
                let texture = split_sky(&mut scene.textures, radiance, 0.0509)?;
                scene.sky = Sky::Environment {
                    texture,
                    strength: 1.0,
                    rotation: 0.0,
                };
            }
            Lighting::FactoryPoint { world } => {
                scene.lights.push(factory_point(norm));
                scene.sky = Sky::Constant(Vec3::splat(world));
            }
            Lighting::Trellis => {
                scene.sky = Sky::Constant(Vec3::splat(0.0509));
                // Made in the normalised frame, so placed through the normalisation.
                let s = norm.scale;
                let at = norm.to_scene(to_meshtrace(DVec3::new(4.0, 1.0, 6.0)));
                scene.lights.push(thousand_watts_at(at, norm));
                let side = 25.0f32;
                scene.lights.push(PunctualLight::Rect {
                    center: norm.to_scene(to_meshtrace(DVec3::new(0.0, 0.0, 10.0))),
                    edge_u: Vec3::X * (side / s),
                    edge_v: Vec3::Z * (side / s),
                    radiance: Vec3::splat(10_000.0 / (std::f32::consts::PI * side * side)),
                });
            }
            Lighting::Suns => {
                scene.sky = Sky::Constant(Vec3::splat(0.0509));
                let h = std::f64::consts::FRAC_1_SQRT_2;
                let suns = [
                    ([3.0, 4.0, 5.0], DVec3::new(0.5, 0.5, -h)),
                    ([2.0, 3.0, 4.0], DVec3::new(-0.5, -0.5, -h)),
                    ([3.0, 4.0, 5.0], DVec3::new(0.5, 0.5, -h)),
                    ([1.0, 2.0, 3.0], DVec3::new(0.0, 0.0, 1.0)),
                ];
                for (k, (choices, travel)) in suns.into_iter().enumerate() {
                    // random.choice of three.
                    let pick = ((3.0 * uniform(uid, OBJECT, k as u32)) as usize).min(2);
                    scene.lights.push(PunctualLight::Directional {
                        direction: to_meshtrace(travel).normalize(),
                        irradiance: Vec3::splat(choices[pick]),
                        shadows: false,
                    });
                }
            }
            Lighting::Wonder3d => {
                scene.sky = Sky::Constant(Vec3::splat(0.4 * 0.5));
                for (irradiance, turn) in [(5.0, 0.0f64), (3.0, 180.0), (3.0, 90.0), (3.0, -90.0)] {
                    // A sun turned about X by `turn` radians travels along Rx (0, 0, −1).
                    let travel = DVec3::new(0.0, turn.sin(), -turn.cos());
                    scene.lights.push(PunctualLight::Directional {
                        direction: to_meshtrace(travel).normalize(),
                        irradiance: Vec3::splat(irradiance),
                        shadows: false,
                    });
                }
            }
            Lighting::Zero123 => {
                scene.lights.push(factory_point(norm));
                scene.sky = Sky::Constant(Vec3::splat(0.0509));
                let u = |dim| uniform(uid, OBJECT, dim);
                let energy = 300.0 + 300.0 * u(0);
                let at = DVec3::new(2.0 * u(1) - 1.0, 2.0 * u(2) - 1.0, 0.5 + u(3));
                let side = 100.0 * norm.scale as f64;
                let radiance = energy / (std::f64::consts::PI * side * side);
                // Facing Blender's −Z, meshtrace's −Y: X × Z = −Y.
                scene.lights.push(PunctualLight::Rect {
                    center: norm.to_scene(to_meshtrace(at)),
                    edge_u: Vec3::X * 100.0,
                    edge_v: Vec3::Z * 100.0,
                    radiance: Vec3::splat(radiance as f32),
                });
            }
        }
        Ok(())
    }
}

/// The base-2 radical inverse of `i`: its bits mirrored about the binary point.
fn radical_inverse_2(i: u32) -> f64 {
    i.reverse_bits() as f64 / 4_294_967_296.0
}

/// The "view" of the numbers an object draws once (its lights), apart from its views'.
const OBJECT: u32 = u32::MAX;
/// The dimension of a shell view's radius, past the direction's (and its redraws').
const SHELL_RADIUS: u32 = 1 << 16;
/// The dimension of a random ring view's elevation.
const RING_ELEVATION: u32 = 0;

/// Blender's factory point light (1,000 W at (4.0762, 1.0055, 5.9039)) in the frame of a
/// mesh that `norm` normalises. It is a root object when the scripts normalise, so it moves
/// with the object: in the mesh's own frame it stays at its Blender position divided by
/// the scale, and its intensity, P / (4π) W/sr as Cycles emits a point light's watts, is
/// divided by the scale squared, so that the object receives what it does in the script.
/// (Blender's light is a sphere of radius 0.1 m, meshtrace's a point: the shadows are
/// harder.) It moves by the script's offset ([`Normalisation::blender_offset`]).
fn factory_point(norm: &Normalisation) -> PunctualLight {
    let normalised = DVec3::new(4.0762, 1.0055, 5.9039) + norm.blender_offset();
    thousand_watts_at(norm.to_scene(to_meshtrace(normalised)), norm)
}

/// A point light of 1,000 W (P / (4π) W/sr, as Cycles emits a point light's watts) placed
/// in the normalised frame of a mesh that `norm` normalises, at `position` in the mesh's
/// own: its intensity over the scale squared gives the object what it gets in the script.
fn thousand_watts_at(position: Vec3, norm: &Normalisation) -> PunctualLight {
    PunctualLight::Point {
        position,
        intensity: Vec3::splat(1000.0 / (4.0 * std::f32::consts::PI) / (norm.scale * norm.scale)),
    }
}

/// Writes `rows`, a 3 × 4 matrix, as NumPy's `.npy` (format 1.0, little-endian float32,
/// C order): what the scripts' `np.save` of a Blender `Matrix` writes, and `np.load` reads.
pub fn write_npy(path: &std::path::Path, rows: &[[f64; 4]; 3]) -> std::io::Result<()> {
    let mut header = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4), }".to_string();
    // Magic (6), version (2) and length (2), then the header padded with spaces and ended
    // by a newline to a multiple of 64 bytes, as NumPy aligns it.
    while !(10 + header.len() + 1).is_multiple_of(64) {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for x in rows.iter().flatten() {
        bytes.extend_from_slice(&(*x as f32).to_le_bytes());
    }
    std::fs::write(path, bytes)
}

/// An environment of radiance `above` over the horizon and `below` under it: an
/// equirectangular image of 256 × 128 texels (its rows blend only within 0.7° of the
/// horizon).
fn split_sky(textures: &mut Textures, above: f32, below: f32) -> Result<u32, SceneError> {
    let (w, h) = (256u32, 128u32);
    let pixels: Vec<image::Rgb<f32>> = (0..h)
        .flat_map(|y| {
            let v = if y < h / 2 { above } else { below };
            (0..w).map(move |_| image::Rgb([v; 3]))
        })
        .collect();
    let mut bytes = Vec::new();
    let invalid = |message: String| SceneError::Invalid {
        path: "preset".into(),
        field: "sky".into(),
        message,
    };
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&pixels, w as usize, h as usize)
        .map_err(|e| invalid(e.to_string()))?;
    let r = TextureRef::environment(TextureSource::Memory {
        name: "preset sky (built in)".into(),
        bytes: bytes.into(),
        format: Some(ImageType::Image(image::ImageFormat::Hdr)),
    });
    textures
        .add(&r, &crate::scene::source::Fs)
        .map_err(|e| match e {
            TextureError::Fatal(e) => e,
            TextureError::Missing(name) => invalid(format!("{name} cannot be read")),
        })
}

/// The horizontal field of view, in degrees, of a lens of `focal` mm on a sensor `width`
/// mm wide (a square image: the vertical one too).
pub fn fov_of_lens(focal: f32, width: f32) -> f32 {
    2.0 * (width / 2.0 / focal).atan().to_degrees()
}

/// A Blender-frame point (Z up) in meshtrace's frame (Y up).
pub fn to_meshtrace(b: DVec3) -> Vec3 {
    Vec3::new(b.x as f32, b.z as f32, -b.y as f32)
}

/// A meshtrace-frame point (Y up) in Blender's frame (Z up): [`to_meshtrace`] undone.
pub fn to_blender(m: Vec3) -> DVec3 {
    DVec3::new(m.x as f64, -(m.z as f64), m.y as f64)
}

/// Objaverse-XL's `metadata.json` of `scene` (read from `file`, before a preset lights it),
/// with what meshtrace knows of the keys the script writes: the file's size, the triangles
/// (the script counts Blender's faces, triangles after its glTF import), vertices,
/// materials and lights, and the box in Blender's frame in the file's units; and the
/// normalisation `norm` that the script applies without saving it.
pub fn metadata(file: &std::path::Path, scene: &Scene, norm: &Normalisation) -> serde_json::Value {
    let size = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    let (lo, hi) = scene
        .framed
        .map_or((Vec3::ZERO, Vec3::ZERO), |b| (b.min, b.max));
    // Blender's Z-up box of a Y-up box: y and z swap, and z's sign turns.
    let (blo, bhi) = (
        to_blender(Vec3::new(lo.x, lo.y, hi.z)),
        to_blender(Vec3::new(hi.x, hi.y, lo.z)),
    );
    serde_json::json!({
        "file_size": size,
        "poly_count": scene.mesh.triangles.len(),
        "vert_count": scene.mesh.positions.len(),
        "material_count": scene.materials.len(),
        "lamp_count": scene.lights.len(),
        "scene_size": {
            "bbox_min": [blo.x, blo.y, blo.z],
            "bbox_max": [bhi.x, bhi.y, bhi.z],
        },
        "normalisation": {
            "scale": norm.scale,
            "offset": norm.blender_offset().to_array(),
        },
    })
}

/// The scripts' normalisation: scaled by 1 / (the bounding box's largest extent) and
/// moved so that the box's centre is the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalisation {
    pub scale: f32,
    /// The box's centre in the mesh's own frame.
    pub centre: Vec3,
    /// Where the scripts' scaled object has its origin, in Blender's frame: the file's one
    /// root node's translation T ([`Scene::root_origin`]), about which the script scales
    /// it; 0 where there is none or the script scales an empty at the origin instead.
    /// The images are the same either way; the offset the script records is not
    /// ([`Normalisation::blender_offset`]).
    pub root: DVec3,
}

impl Normalisation {
    /// The normalisation of a mesh of bounds `b`; `None` for an empty or flat-less box.
    pub fn of(b: &Aabb) -> Option<Self> {
        let extent = (b.max - b.min).max_element();
        (extent.is_finite() && extent > 0.0).then(|| Self {
            scale: 1.0 / extent,
            centre: (b.min + b.max) * 0.5,
            root: DVec3::ZERO,
        })
    }

    /// The normalisation of Wonder3D's orthographic script: scaled by 1 / (the bounding
    /// box's diagonal) and centred the same way.
    pub fn of_diagonal(b: &Aabb) -> Option<Self> {
        let diagonal = (b.max - b.min).length();
        (diagonal.is_finite() && diagonal > 0.0).then(|| Self {
            scale: 1.0 / diagonal,
            centre: (b.min + b.max) * 0.5,
            root: DVec3::ZERO,
        })
    }

    /// The translation the script records, in Blender's frame: it scales its object by s
    /// about the object's origin T ([`Normalisation::root`]), then moves it by this offset,
    /// −s c − (1 − s) T, so that a point p of the file lands at s p − s c whatever T is.
    /// Objects that are roots beside the mesh (the factory light) move by it too.
    pub fn blender_offset(&self) -> DVec3 {
        let s = self.scale as f64;
        -s * to_blender(self.centre) - (1.0 - s) * self.root
    }

    /// Where the script's object scales about: `root`, the file's one root node's
    /// translation in the mesh's frame, unless `preset` scales an empty at the origin.
    pub fn with_root(self, preset: &Preset, root: Option<Vec3>) -> Self {
        // Objaverse-XL parents every root object to an empty at the origin, and scales
        // that (which is why its cameras aim at the file's origin).
        let root = match (preset.aim, root) {
            (Aim::Centre, Some(t)) => to_blender(t),
            _ => DVec3::ZERO,
        };
        Self { root, ..self }
    }

    /// A normalised point back in the mesh's frame.
    pub fn to_scene(&self, n: Vec3) -> Vec3 {
        n / self.scale + self.centre
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recorded_offset_is_the_scripts_for_a_translated_root() {
        // A box from (1, 2, 3) to (3, 4, 5) in the file (Y up): s = 1/2, c = (2, 3, 4),
        // Blender's c = (2, −4, 3). Its one root node at (1, 0, 0) (Blender's too).
        let b = Aabb {
            min: Vec3::new(1.0, 2.0, 3.0),
            max: Vec3::new(3.0, 4.0, 5.0),
        };
        let trellis = Preset::named("trellis").unwrap();
        let norm = trellis.normalisation(&b).unwrap();
        // Scaled about the origin: −s c.
        assert_eq!(norm.blender_offset(), DVec3::new(-1.0, 2.0, -1.5));
        // Scaled about T = (1, 0, 0): the box's centre goes to T + s (c − T) = (1.5, −2,
        // 1.5), and the script moves it back to the origin.
        let root = Some(Vec3::X);
        let rooted = norm.with_root(&trellis, root);
        assert_eq!(rooted.blender_offset(), DVec3::new(-1.5, 2.0, -1.5));
        // Either way a point of the file lands at s p − s c.
        let p = DVec3::new(3.0, -2.0, 5.0);
        let moved = DVec3::X + 0.5 * (p - DVec3::X) + rooted.blender_offset();
        assert_eq!(moved, 0.5 * p + norm.blender_offset());
        // Objaverse-XL scales an empty at the origin, whatever the file's root.
        let xl = Preset::named("objaverse-xl").unwrap();
        assert_eq!(
            norm.with_root(&xl, root).blender_offset(),
            norm.blender_offset()
        );
    }

    /// The scripts' light paths reach each image's request, under a manifest's `[render]`.
    #[test]
    fn presets_ask_for_their_scripts_bounce_limits() {
        let limits = |r: &RenderRequest| {
            (
                r.max_depth,
                r.diffuse_bounces,
                r.glossy_bounces,
                r.transmission_bounces,
            )
        };
        for name in [
            "zero123",
            "objaverse",
            "objaverse-xl",
            "syncdreamer",
            "trellis",
        ] {
            let r = Preset::named(name).expect("preset").request();
            assert_eq!(limits(&r), (Some(14), Some(1), Some(1), Some(3)), "{name}");
        }
        let wonder3d = Preset::named("wonder3d").expect("preset").request();
        assert_eq!(limits(&wonder3d), (Some(5), Some(3), Some(0), Some(0)));
        let manifest = RenderRequest {
            diffuse_bounces: Some(4),
            ..RenderRequest::default()
        };
        let r = manifest.over(&wonder3d);
        assert_eq!(limits(&r), (Some(5), Some(4), Some(0), Some(0)));
    }
}
