//! View transforms: how an image's linear radiance becomes the values of an 8- or 16-bit
//! file, as Blender's colour management makes them for an sRGB display.
//!
//! `standard` is the sRGB curve, clamped. `filmic` and `agx` are Blender's views of those
//! names (Filmic is the default of Blender 2.80–3.6, AgX of 4.0 and later), which the
//! dataset scripts' images went through without setting either. Each is the chain that
//! Blender's `config.ocio` gives it, evaluated here without OpenColorIO:
//!
//! - Filmic: the log2 allocation over [−12.473931188, 12.526068812] stops of linear
//!   Rec.709, the 33³ LUT `filmic/filmic_desat_33.cube` (tetrahedral), a uniform allocation
//!   of [0, 0.66] and the 1D LUT `filmic/filmic_to_0-70_1-03.spi1d` (linear): the display's
//!   encoded values.
//! - AgX: linear Rec.709 into FilmLight E-Gamut, the log2 allocation over
//!   [−12.47393, 12.5260688117], the 57³ LUT `luts/AgX_Base_sRGB.cube` (tetrahedral), the
//!   exponent 2.4 (Rec.1886), then the sRGB curve.
//!
//! The LUTs are Blender's data, not meshtrace's to redistribute: they are read from the
//! `datafiles/colormanagement` folder of a Blender 4.0 or later ([`lut_folder`]).

use super::{FilmError, srgb};
use glam::{DMat3, DVec3, Vec3};
use std::path::{Path, PathBuf};

/// The environment variable that names Blender's `datafiles/colormanagement` folder.
pub const LUT_FOLDER_VAR: &str = "MESHTRACE_BLENDER_LUTS";

/// Where Debian's and Ubuntu's `blender-data` package (Blender 4.0 and later) puts it.
const SYSTEM_LUT_FOLDER: &str = "/usr/share/blender/datafiles/colormanagement";

/// A view transform, by the name of Blender's view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ViewTransform {
    /// The sRGB curve of the clamped radiance.
    #[default]
    Standard,
    /// Blender's Filmic (base contrast).
    Filmic,
    /// Blender's AgX (no look).
    Agx,
}

impl ViewTransform {
    /// The names on the command line and in manifests.
    pub const NAMES: [(&'static str, ViewTransform); 3] = [
        ("standard", ViewTransform::Standard),
        ("filmic", ViewTransform::Filmic),
        ("agx", ViewTransform::Agx),
    ];

    /// The files of [`lut_folder`] the transform reads.
    pub fn lut_files(self) -> &'static [&'static str] {
        match self {
            ViewTransform::Standard => &[],
            ViewTransform::Filmic => &[FILMIC_CUBE, FILMIC_CURVE],
            ViewTransform::Agx => &[AGX_CUBE],
        }
    }
}

const FILMIC_CUBE: &str = "filmic/filmic_desat_33.cube";
const FILMIC_CURVE: &str = "filmic/filmic_to_0-70_1-03.spi1d";
const AGX_CUBE: &str = "luts/AgX_Base_sRGB.cube";

/// Linear Rec.709 (D65) to linear FilmLight E-Gamut, as Blender's config composes it:
/// E-Gamut's matrix from CIE XYZ (D65) times the inverse of Rec.709's matrix to XYZ (both
/// spaces pass through XYZ with illuminant E there, by one matrix, which cancels).
fn rec709_to_e_gamut() -> DMat3 {
    let rows = |m: [[f64; 3]; 3]| DMat3::from_cols_array_2d(&m).transpose();
    let xyz_to_rec709 = rows([
        [3.2409699, -1.5373832, -0.4986108],
        [-0.9692436, 1.8759675, 0.0415551],
        [0.0556301, -0.2039770, 1.0569715],
    ]);
    let xyz_to_e_gamut = rows([
        [1.5250528, -0.3159135, -0.1226583],
        [-0.5091526, 1.3333274, 0.1382844],
        [0.0957153, 0.0508974, 0.7879558],
    ]);
    xyz_to_e_gamut * xyz_to_rec709.inverse()
}

/// A view transform ready to apply: its LUTs read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DisplayTransform {
    view: ViewTransform,
    luts: Luts,
}

#[derive(Clone, Debug, Default, PartialEq)]
enum Luts {
    #[default]
    None,
    Filmic {
        cube: Cube,
        curve: Vec<f32>,
    },
    Agx {
        to_e_gamut: DMat3,
        cube: Cube,
    },
}

impl DisplayTransform {
    /// `view` with its LUTs read from [`lut_folder`]; an error names the file it lacks or
    /// cannot read, and how to provide it.
    pub fn load(view: ViewTransform) -> Result<Self, FilmError> {
        let luts = match view {
            ViewTransform::Standard => Luts::None,
            ViewTransform::Filmic => {
                let folder = lut_folder(view)?;
                Luts::Filmic {
                    cube: Cube::read(&folder.join(FILMIC_CUBE))?,
                    curve: read_spi1d(&folder.join(FILMIC_CURVE))?,
                }
            }
            ViewTransform::Agx => Luts::Agx {
                to_e_gamut: rec709_to_e_gamut(),
                cube: Cube::read(&lut_folder(view)?.join(AGX_CUBE))?,
            },
        };
        Ok(Self { view, luts })
    }

    pub fn view(&self) -> ViewTransform {
        self.view
    }

    /// The display-encoded values in [0, 1] of linear Rec.709 radiance `c` (NaN as 0).
    pub fn encode(&self, c: Vec3) -> [f32; 3] {
        let c = c.to_array().map(|v| if v.is_nan() { 0.0 } else { v });
        match &self.luts {
            Luts::None => c.map(srgb),
            Luts::Filmic { cube, curve } => {
                let log = c.map(|v| log2_allocation(v.into(), -12.473931188, 12.526068812));
                cube.tetrahedral(log)
                    .map(|v| interpolate_1d(curve, v / 0.66))
            }
            Luts::Agx { to_e_gamut, cube } => {
                let e = (*to_e_gamut * DVec3::from(c.map(f64::from))).to_array();
                let log = e.map(|v| log2_allocation(v, -12.47393, 12.5260688117));
                cube.tetrahedral(log).map(|v| srgb(v.max(0.0).powf(2.4)))
            }
        }
    }
}

/// Blender's `datafiles/colormanagement` folder with the files `view` reads: the one that
/// [`LUT_FOLDER_VAR`] names, else Debian's `blender-data`'s.
pub fn lut_folder(view: ViewTransform) -> Result<PathBuf, FilmError> {
    let (folder, from) = match std::env::var_os(LUT_FOLDER_VAR) {
        Some(f) if !f.is_empty() => (
            PathBuf::from(f),
            format!("the folder {LUT_FOLDER_VAR} names"),
        ),
        _ => (
            PathBuf::from(SYSTEM_LUT_FOLDER),
            format!("{LUT_FOLDER_VAR} is unset"),
        ),
    };
    match view.lut_files().iter().find(|f| !folder.join(f).is_file()) {
        None => Ok(folder),
        Some(missing) => Err(FilmError::MissingLut {
            file: folder.join(missing).display().to_string(),
            from,
        }),
    }
}

/// OpenColorIO's `lg2` allocation: `log2(x)` mapped from [`lo`, `hi`] onto [0, 1] (values
/// at or below 0 taken as the smallest normal float, as OpenColorIO's log does).
fn log2_allocation(x: f64, lo: f64, hi: f64) -> f32 {
    ((x.max(f32::MIN_POSITIVE as f64).log2() - lo) / (hi - lo)) as f32
}

/// A 3D LUT of a `.cube` file over the domain [0, 1]³: `size`³ RGB entries, red the
/// fastest-varying index.
#[derive(Clone, Debug, Default, PartialEq)]
struct Cube {
    size: usize,
    table: Vec<[f32; 3]>,
}

impl Cube {
    /// Reads an Iridas/Resolve `.cube` 3D LUT (`LUT_3D_SIZE`, a [0, 1] domain).
    fn read(path: &Path) -> Result<Self, FilmError> {
        let text = read_text(path)?;
        let bad = |line: usize, message: String| FilmError::BadLut {
            path: path.display().to_string(),
            line,
            message,
        };
        let mut size = 0;
        let mut table = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let mut words = line.split_whitespace();
            let Some(first) = words.next() else { continue };
            match first {
                _ if first.starts_with('#') => {}
                "TITLE" => {}
                "LUT_3D_SIZE" => {
                    size = words
                        .next()
                        .and_then(|w| w.parse().ok())
                        .filter(|&n: &usize| (2..=256).contains(&n))
                        .ok_or_else(|| bad(i + 1, "LUT_3D_SIZE must be 2 to 256".into()))?;
                }
                "DOMAIN_MIN" | "DOMAIN_MAX" => {
                    let want = if first == "DOMAIN_MIN" { 0.0 } else { 1.0 };
                    let values: Vec<f32> = words.filter_map(|w| w.parse().ok()).collect();
                    if values != [want; 3] {
                        return Err(bad(i + 1, format!("{first} must be {want} {want} {want}")));
                    }
                }
                _ => {
                    let values: Vec<f32> = std::iter::once(first)
                        .chain(words)
                        .map(|w| w.parse::<f32>())
                        .collect::<Result<_, _>>()
                        .map_err(|_| bad(i + 1, format!("`{}` is not 3 numbers", line.trim())))?;
                    match values[..] {
                        [r, g, b] => table.push([r, g, b]),
                        _ => return Err(bad(i + 1, format!("`{}` is not 3 numbers", line.trim()))),
                    }
                }
            }
        }
        if size == 0 || table.len() != size * size * size {
            return Err(bad(
                text.lines().count(),
                format!(
                    "{} entries for LUT_3D_SIZE {size} (it needs {})",
                    table.len(),
                    size * size * size
                ),
            ));
        }
        Ok(Self { size, table })
    }

    /// The LUT at `c` (each component clamped to [0, 1]) by tetrahedral interpolation, as
    /// OpenColorIO's CPU renderer does it.
    fn tetrahedral(&self, c: [f32; 3]) -> [f32; 3] {
        let n = self.size;
        let last = (n - 1) as f32;
        let mut base = [0usize; 3];
        let mut f = [0f32; 3];
        for k in 0..3 {
            let x = c[k].clamp(0.0, 1.0) * last;
            let i = (x.floor() as usize).min(n - 2);
            base[k] = i;
            f[k] = x - i as f32;
        }
        let at = |dr: usize, dg: usize, db: usize| {
            Vec3::from(self.table[((base[2] + db) * n + base[1] + dg) * n + base[0] + dr])
        };
        let (r, g, b) = (f[0], f[1], f[2]);
        let (c000, c111) = (at(0, 0, 0), at(1, 1, 1));
        let v = if r > g {
            if g > b {
                (1.0 - r) * c000 + (r - g) * at(1, 0, 0) + (g - b) * at(1, 1, 0) + b * c111
            } else if r > b {
                (1.0 - r) * c000 + (r - b) * at(1, 0, 0) + (b - g) * at(1, 0, 1) + g * c111
            } else {
                (1.0 - b) * c000 + (b - r) * at(0, 0, 1) + (r - g) * at(1, 0, 1) + g * c111
            }
        } else if b > g {
            (1.0 - b) * c000 + (b - g) * at(0, 0, 1) + (g - r) * at(0, 1, 1) + r * c111
        } else if b > r {
            (1.0 - g) * c000 + (g - b) * at(0, 1, 0) + (b - r) * at(0, 1, 1) + r * c111
        } else {
            (1.0 - g) * c000 + (g - r) * at(0, 1, 0) + (r - b) * at(1, 1, 0) + b * c111
        };
        v.to_array()
    }
}

/// Reads a Sony Imageworks `.spi1d` 1D LUT of one component over the domain [0, 1].
fn read_spi1d(path: &Path) -> Result<Vec<f32>, FilmError> {
    let text = read_text(path)?;
    let bad = |line: usize, message: String| FilmError::BadLut {
        path: path.display().to_string(),
        line,
        message,
    };
    let mut length = None;
    let mut values = Vec::new();
    let mut inside = false;
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words[..] {
            [] => {}
            ["{"] => inside = true,
            ["}"] => inside = false,
            [word] if inside => values.push(
                word.parse::<f32>()
                    .map_err(|_| bad(i + 1, format!("`{word}` is not a number")))?,
            ),
            ["From", lo, hi] if (lo.parse(), hi.parse()) != (Ok(0.0f32), Ok(1.0f32)) => {
                return Err(bad(i + 1, "the domain must be `From 0 1`".into()));
            }
            ["Components", n] if n != "1" => {
                return Err(bad(i + 1, "only 1-component LUTs are read".into()));
            }
            ["Length", n] => length = n.parse::<usize>().ok(),
            _ => {}
        }
    }
    match length {
        Some(n) if n >= 2 && n == values.len() => Ok(values),
        _ => Err(bad(
            text.lines().count(),
            format!("{} values where `Length` gives {length:?}", values.len()),
        )),
    }
}

/// The 1D LUT at `x` clamped to [0, 1], linearly interpolated.
fn interpolate_1d(lut: &[f32], x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0) * (lut.len() - 1) as f32;
    let i = (x.floor() as usize).min(lut.len() - 2);
    let f = x - i as f32;
    lut[i] * (1.0 - f) + lut[i + 1] * f
}

fn read_text(path: &Path) -> Result<String, FilmError> {
    std::fs::read_to_string(path).map_err(|e| FilmError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}
