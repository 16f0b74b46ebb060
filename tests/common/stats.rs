//! Statistics and error bookkeeping: means with their standard errors, relative errors with
//! a floor, and trackers that report the largest error ([`Worst`]), count tolerated cases
//! ([`Tally`]) and collect hard failures ([`Failures`]), each printing what it saw.

use glam::Vec3;
use meshtrace::film::Film;

/// Mean and unbiased variance of `values`.
fn mean_and_variance<T: Copy + Into<f64>>(values: &[T]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().map(|&v| v.into()).sum::<f64>() / n;
    let var = values
        .iter()
        .map(|&v| (v.into() - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, var)
}

/// Mean and standard error of the mean of independent values (pixels, samples).
pub fn mean_and_stderr<T: Copy + Into<f64>>(values: &[T]) -> (f64, f64) {
    let (mean, var) = mean_and_variance(values);
    (mean, (var / values.len() as f64).sqrt())
}

/// Mean and standard deviation of `values`.
pub fn mean_and_sd<T: Copy + Into<f64>>(values: &[T]) -> (f64, f64) {
    let (mean, var) = mean_and_variance(values);
    (mean, var.sqrt())
}

/// Relative difference with a floor on the magnitude: `|a - b| / max(|a|, |b|, floor)`.
/// With `floor = abs / rel`, `err <= rel` means `|a - b| <= rel * max(|a|, |b|) + abs`
/// (near enough). Equal values (infinities included) give 0, NaN or one infinity gives inf.
pub fn rel(a: f32, b: f32, floor: f32) -> f64 {
    if a == b {
        return 0.0;
    }
    if !(a.is_finite() && b.is_finite()) {
        return f64::INFINITY;
    }
    (a as f64 - b as f64).abs() / (a.abs().max(b.abs()).max(floor)) as f64
}

/// The largest [`rel`] of the three components.
pub fn rel3(a: Vec3, b: Vec3, floor: f32) -> f64 {
    (0..3).map(|i| rel(a[i], b[i], floor)).fold(0.0, f64::max)
}

/// The largest error seen for one quantity, with the case it came from. Each error is
/// checked against a tolerance, fixed (`limit`) or given per case (for ill-conditioned
/// cases); a NaN error counts as infinite.
pub struct Worst {
    what: String,
    limit: f64,
    /// The largest error / tolerance (must stay <= 1) and the largest raw error.
    max_ratio: f64,
    max: f64,
    at: String,
    n: usize,
    /// Whether some case had a tolerance above `limit`.
    widened: bool,
    /// Whether some error exceeded its tolerance (compared directly, not through the ratio).
    exceeded: bool,
}

impl Worst {
    pub fn new(what: impl Into<String>, limit: f64) -> Self {
        Self {
            what: what.into(),
            limit,
            max_ratio: 0.0,
            max: 0.0,
            at: String::new(),
            n: 0,
            widened: false,
            exceeded: false,
        }
    }

    /// Adds an error to be checked against `limit`.
    pub fn add(&mut self, err: f64, case: impl FnOnce() -> String) {
        self.add_tol(err, self.limit, case);
    }

    /// Adds an error to be checked against its own tolerance `tol`.
    pub fn add_tol(&mut self, err: f64, tol: f64, case: impl FnOnce() -> String) {
        self.n += 1;
        self.widened |= tol > self.limit;
        let err = if err.is_nan() { f64::INFINITY } else { err };
        self.max = self.max.max(err);
        self.exceeded |= err > tol;
        if err / tol > self.max_ratio {
            self.max_ratio = err / tol;
            self.at = format!("{} (error {err:.3e}, tolerance {tol:.3e})", case());
        }
    }

    pub fn report(&self) -> String {
        format!(
            "{}: max error {:.3e} (tolerance {:.0e}{}; max error/tolerance {:.3}) over {} values",
            self.what,
            self.max,
            self.limit,
            if self.widened {
                ", widened where ill-conditioned"
            } else {
                ""
            },
            self.max_ratio,
            self.n
        )
    }

    /// Prints the report, prefixed by `entry`, and fails if any error exceeded its tolerance.
    pub fn check(&self, entry: &str) {
        eprintln!("{entry}: {}", self.report());
        assert!(
            self.max_ratio <= 1.0 && !self.exceeded,
            "{entry}: {}; worst case: {}",
            self.report(),
            self.at
        );
    }
}

/// A count of cases of some kind that may occur, bounded by a fraction of all cases.
pub struct Tally {
    what: &'static str,
    max_fraction: f64,
    pub count: usize,
    examples: Vec<String>,
}

impl Tally {
    pub fn new(what: &'static str, max_fraction: f64) -> Self {
        Self {
            what,
            max_fraction,
            count: 0,
            examples: Vec::new(),
        }
    }

    pub fn add(&mut self, case: impl FnOnce() -> String) {
        self.count += 1;
        if self.examples.len() < 3 {
            self.examples.push(case());
        }
    }

    /// Prints the count and its first examples, and fails if it exceeds its fraction of
    /// `total`.
    pub fn check(&self, entry: &str, total: usize) {
        let frac = self.count as f64 / total as f64;
        eprintln!(
            "{entry}: {}: {} of {total} ({:.4}%, limit {:.4}%)",
            self.what,
            self.count,
            100.0 * frac,
            100.0 * self.max_fraction
        );
        for e in &self.examples {
            eprintln!("  e.g. {e}");
        }
        assert!(
            frac <= self.max_fraction,
            "{entry}: {}: {} of {total} cases exceed {:.4}%; e.g.\n{}",
            self.what,
            self.count,
            100.0 * self.max_fraction,
            self.examples.join("\n")
        );
    }
}

/// Hard failures: any one fails the test (the first few are shown).
pub struct Failures {
    entry: &'static str,
    list: Vec<String>,
    pub count: usize,
}

impl Failures {
    pub fn new(entry: &'static str) -> Self {
        Self {
            entry,
            list: Vec::new(),
            count: 0,
        }
    }

    pub fn add(&mut self, msg: impl FnOnce() -> String) {
        self.count += 1;
        if self.list.len() < 5 {
            self.list.push(msg());
        }
    }

    pub fn check(&self, total: usize) {
        assert!(
            self.count == 0,
            "{}: {} of {total} cases differ from the CPU; first:\n{}",
            self.entry,
            self.count,
            self.list.join("\n")
        );
    }
}

/// The fraction of pixel channels of `gpu` within float rounding (1e-3 relative) of `cpu`.
pub fn fraction_close(gpu: &[f64], cpu: &[f64]) -> f64 {
    let close = gpu
        .iter()
        .zip(cpu)
        .filter(|(g, c)| (*g - *c).abs() <= 1e-3 * c.abs() + 1e-5)
        .count();
    close as f64 / gpu.len() as f64
}

/// The share of pixels whose paths traced as many rays in `a` as in `b` (the films'
/// [`Film::RAYS`] channels): paths that replay each other.
pub fn same_rays(a: &Film, b: &Film) -> f64 {
    let rays = |f: &Film| f.channel(Film::RAYS).expect("a rays channel").data.clone();
    let (a, b) = (rays(a), rays(b));
    a.iter().zip(&b).filter(|(x, y)| x == y).count() as f64 / a.len() as f64
}

/// A film's mean pixel values, channel by channel.
pub fn pixel_channels(film: &Film) -> Vec<f64> {
    film.mean()
        .iter()
        .flat_map(|p| p.to_array())
        .map(f64::from)
        .collect()
}

/// Asserts that each channel's image mean of `film` lies within 5 standard errors of
/// `expect`, and that the standard error is small enough (0.2% of it) for that to test.
pub fn assert_mean(name: &str, device: &str, film: &meshtrace::film::Film, expect: glam::Vec3) {
    assert_mean_within(name, device, film, expect, 0.0);
}

/// [`assert_mean`] allowing `rel` of the expected value on top of the 5 standard errors:
/// for images whose pixels share one path but for a few random choices, whose standard
/// error can be near 0 while float rounding is not.
pub fn assert_mean_within(
    name: &str,
    device: &str,
    film: &meshtrace::film::Film,
    expect: glam::Vec3,
    rel: f64,
) {
    let mean = film.mean();
    for c in 0..3 {
        let values: Vec<f32> = mean.iter().map(|p| p[c]).collect();
        let (m, se) = mean_and_stderr(&values);
        let e = expect[c] as f64;
        eprintln!("{name}/{device}: channel {c}: mean {m:.6}, expected {e:.6}, se {se:.6}");
        assert!(
            se < 0.002 * e,
            "{name}/{device}: channel {c}: standard error {se} too large to test"
        );
        assert!(
            (m - e).abs() < 5.0 * se + rel * e + 1e-6,
            "{name}/{device}: channel {c}: mean {m}, expected {e} (se {se})"
        );
    }
}
