//! Pearson's chi-square goodness-of-fit test of sampled directions (as Mitsuba's and pbrt's
//! BSDF tests do): directions binned over (cos theta, phi) about an axis in
//! `COS_BINS` x `PHI_BINS` cells of equal solid angle, expected counts from integrating the
//! pdf over each cell (adaptively), categories with few expected samples pooled, and the
//! p-value from the chi-square survival function (regularised incomplete gamma function).

use glam::{DVec3, Vec3};
use std::f64::consts::PI;

use super::gamma::ln_gamma_q;
use super::materials::mirror;

pub const COS_BINS: usize = 10;
pub const PHI_BINS: usize = 20;
pub const CELLS: usize = COS_BINS * PHI_BINS;
/// Categories expected to hold fewer samples than this are pooled.
pub const MIN_EXPECTED: f64 = 5.0;

/// Cells over (cos theta', phi') about the axis `n` of the frame (t, b, n): COS_BINS equal
/// steps of cos theta' in [cos_min, 1] (equal solid angles) by PHI_BINS of phi'. Directions
/// with cos theta' < cos_min, and refused samples, fall in one extra "outside" category.
#[derive(Clone, Debug)]
pub struct Binning {
    t: DVec3,
    b: DVec3,
    n: DVec3,
    cos_min: f64,
    /// The binning in messages.
    pub what: String,
}

impl Binning {
    /// The upper hemisphere of the local frame.
    pub fn local() -> Self {
        Self {
            t: DVec3::X,
            b: DVec3::Y,
            n: DVec3::Z,
            cos_min: 0.0,
            what: "local (cos theta in [0, 1], phi)".into(),
        }
    }

    /// A cap of half-angle `theta_max` about `axis`.
    pub fn around(axis: Vec3, theta_max: f64) -> Self {
        let n = axis.as_dvec3().normalize();
        let (t, b) = n.any_orthonormal_pair();
        Self {
            t,
            b,
            n,
            cos_min: theta_max.cos(),
            what: format!(
                "about the mirror direction, theta' < {:.1} deg",
                theta_max.to_degrees()
            ),
        }
    }

    /// The cap about the mirror direction of `wo` for a GGX lobe of `alpha`: 10 alpha, which
    /// holds most of the lobe (its reflected directions spread about 2 alpha), at most pi/2.
    pub fn lobe(wo: Vec3, alpha: f32) -> Self {
        Self::around(mirror(wo), (10.0 * alpha as f64).min(PI / 2.0))
    }

    fn cos_step(&self) -> f64 {
        (1.0 - self.cos_min) / COS_BINS as f64
    }

    pub fn direction(&self, c: f64, phi: f64) -> DVec3 {
        let s = (1.0 - c * c).max(0.0).sqrt();
        s * phi.cos() * self.t + s * phi.sin() * self.b + c * self.n
    }

    pub fn cell(&self, w: Vec3) -> Option<usize> {
        let w = w.as_dvec3();
        let c = w.dot(self.n);
        if c.is_nan() || c < self.cos_min {
            return None;
        }
        let ci = (((c - self.cos_min) / self.cos_step()) as usize).min(COS_BINS - 1);
        let mut phi = w.dot(self.b).atan2(w.dot(self.t));
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let pj = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
        Some(ci * PHI_BINS + pj)
    }

    /// Expected counts of `n` samples of `pdf` per cell, and the "outside" remainder
    /// (n minus their sum, at least 0). The solid angle element is d(cos theta) d(phi), and
    /// each cell starts as 16 x 16 midpoint sub-samples (4 x 4 rectangles, each a 4 x 4
    /// midpoint rule); a rectangle whose rule disagrees with the sum of its four quarters'
    /// by more than its share of 1% of the cell count's standard deviation is split, down
    /// to 1/65536 of a cell side, so narrow peaks and the horizon are resolved. Returns the
    /// disagreement left where the depth limit stopped refinement, in standard deviations.
    pub fn expected(&self, pdf: &dyn Fn(Vec3) -> f64, n: f64) -> (Vec<f64>, f64) {
        let dc = self.cos_step();
        let dphi = 2.0 * PI / PHI_BINS as f64;
        let mut worst = 0.0f64;
        let mut e: Vec<f64> = (0..CELLS)
            .map(|cell| {
                let c0 = self.cos_min + (cell / PHI_BINS) as f64 * dc;
                let p0 = (cell % PHI_BINS) as f64 * dphi;
                let rects: Vec<Rect> = (0..16)
                    .map(|k| Rect {
                        c0: c0 + (k / 4) as f64 * dc / 4.0,
                        p0: p0 + (k % 4) as f64 * dphi / 4.0,
                        dc: dc / 4.0,
                        dp: dphi / 4.0,
                    })
                    .collect();
                let coarse: Vec<f64> = rects.iter().map(|r| self.rule(pdf, r)).collect();
                let estimate = coarse.iter().sum::<f64>() * n;
                let tol = 0.01 * estimate.max(1.0).sqrt() / n / 16.0;
                let mut left = 0.0;
                let p: f64 = rects
                    .iter()
                    .zip(&coarse)
                    .map(|(r, &whole)| self.adaptive(pdf, r, whole, tol, 0, &mut left))
                    .sum();
                worst = worst.max(left * n / (p * n).max(1.0).sqrt());
                p * n
            })
            .collect();
        let total: f64 = e.iter().sum();
        e.push((n - total).max(0.0));
        (e, worst)
    }

    /// The 4 x 4 midpoint rule of `pdf` over a rectangle of (cos theta', phi').
    fn rule(&self, pdf: &dyn Fn(Vec3) -> f64, r: &Rect) -> f64 {
        let mut sum = 0.0;
        for a in 0..4 {
            for b in 0..4 {
                let c = r.c0 + (a as f64 + 0.5) * r.dc / 4.0;
                let phi = r.p0 + (b as f64 + 0.5) * r.dp / 4.0;
                sum += pdf(self.direction(c, phi).as_vec3().normalize());
            }
        }
        sum * r.dc * r.dp / 16.0
    }

    /// Adaptive refinement of `whole`, the rule over `r`, by quartering.
    fn adaptive(
        &self,
        pdf: &dyn Fn(Vec3) -> f64,
        r: &Rect,
        whole: f64,
        tol: f64,
        depth: u32,
        left: &mut f64,
    ) -> f64 {
        let kids = r.quarters();
        let parts = kids.each_ref().map(|k| self.rule(pdf, k));
        let sum: f64 = parts.iter().sum();
        let diff = (sum - whole).abs();
        if diff <= tol {
            return sum;
        }
        if depth >= 14 {
            *left += diff;
            return sum;
        }
        kids.iter()
            .zip(parts)
            .map(|(k, p)| self.adaptive(pdf, k, p, tol / 2.0, depth + 1, left))
            .sum()
    }
}

/// A rectangle of (cos theta', phi') from (c0, p0), of sides (dc, dp).
#[derive(Clone, Copy, Debug)]
struct Rect {
    c0: f64,
    p0: f64,
    dc: f64,
    dp: f64,
}

impl Rect {
    fn quarters(&self) -> [Rect; 4] {
        let (dc, dp) = (self.dc / 2.0, self.dp / 2.0);
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(i, j)| Rect {
            c0: self.c0 + i * dc,
            p0: self.p0 + j * dp,
            dc,
            dp,
        })
    }
}

/// The outcome of one chi-square test.
#[derive(Debug)]
pub struct Chi2 {
    pub chi2: f64,
    pub dof: usize,
    pub p: f64,
    /// The categories pooled for too few expected samples.
    pub pooled: usize,
}

/// Pearson's chi-square statistic of `observed` against `expected` counts, pooling the
/// categories with expected counts below MIN_EXPECTED (smallest first, until the pool
/// reaches it), as Mitsuba's `ChiSquareTest` does. Samples in a category that should be
/// empty are an error of their own.
pub fn chi2_test(observed: &[f64], expected: &[f64], n: f64) -> Result<Chi2, String> {
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_o, mut pool_e, mut pooled) = (0.0, 0.0, 0);
    let (mut chi2, mut dof) = (0.0, 0usize);
    for i in order {
        let (o, e) = (observed[i], expected[i]);
        if e < 1e-9 * n && o > 1e-5 * n {
            return Err(format!(
                "{o} samples in category {i}, whose expected count is {e:.3e}"
            ));
        }
        if e < MIN_EXPECTED || (pool_e > 0.0 && pool_e < MIN_EXPECTED) {
            pool_o += o;
            pool_e += e;
            pooled += 1;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    }
    if dof < 2 {
        return Err(format!("only {dof} categories after pooling"));
    }
    let dof = dof - 1;
    Ok(Chi2 {
        chi2,
        dof,
        p: chi2_survival(chi2, dof as f64),
        pooled,
    })
}

/// The regularised upper incomplete gamma function Q(a, x).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    ln_gamma_q(a, x).exp()
}

/// P(X >= chi2) for X chi-square distributed with `dof` degrees of freedom.
pub fn chi2_survival(chi2: f64, dof: f64) -> f64 {
    gamma_q(0.5 * dof, 0.5 * chi2)
}

/// Chi-square of the directions `wis` (None: refused) drawn for `wo`, against `pdf`.
pub fn chi2_of(
    wis: &[Option<Vec3>],
    bin: &Binning,
    pdf: &dyn Fn(Vec3) -> f64,
) -> (Result<Chi2, String>, f64) {
    let n = wis.len() as f64;
    let mut observed = vec![0.0; CELLS + 1];
    for wi in wis {
        observed[wi.and_then(|w| bin.cell(w)).unwrap_or(CELLS)] += 1.0;
    }
    let (expected, integration) = bin.expected(pdf, n);
    (chi2_test(&observed, &expected, n), integration)
}

/// The outcome in messages.
pub fn show_chi2(r: &Result<Chi2, String>) -> String {
    match r {
        Ok(c) => format!(
            "chi2 {:.1}, dof {}, p {:.4} ({} pooled)",
            c.chi2, c.dof, c.p, c.pooled
        ),
        Err(e) => e.clone(),
    }
}

/// The per-test significance level that keeps a family of `tests` independent tests at the
/// family-wise `confidence` (Sidak's correction, as pbrt-v3's BSDF chi-square tests correct
/// theirs): each p-value must exceed it.
pub fn sidak_level(confidence: f64, tests: i32) -> f64 {
    1.0 - confidence.powf(1.0 / tests as f64)
}
