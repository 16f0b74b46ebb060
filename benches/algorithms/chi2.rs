//! Pearson's chi-square test of sampled directions against a density, over cells of equal
//! solid angle (bands of equal steps of cos theta about an axis, times steps of phi), with
//! the p-value from the regularised upper incomplete gamma function, in logs so that the
//! far tail a biased sampler reaches is a number rather than 0.

use glam::DVec3;
use std::f64::consts::PI;

// The gamma functions the suite's own chi-square tests use.
#[path = "../../tests/common/gamma.rs"]
mod gamma;
pub use gamma::ln_gamma_q;

/// Cells over (cos theta, phi) about +Z: `cos_bins` equal steps of cos theta in
/// `cos_min..1` (-1 for the sphere, 0 for the upper hemisphere) by `phi_bins` of phi.
#[derive(Clone, Copy, Debug)]
pub struct Cells {
    pub cos_min: f64,
    pub cos_bins: usize,
    pub phi_bins: usize,
}

impl Cells {
    pub const SPHERE: Cells = Cells {
        cos_min: -1.0,
        cos_bins: 20,
        phi_bins: 40,
    };
    pub const HEMISPHERE: Cells = Cells {
        cos_min: 0.0,
        cos_bins: 10,
        phi_bins: 40,
    };

    pub fn len(&self) -> usize {
        self.cos_bins * self.phi_bins
    }

    fn cos_step(&self) -> f64 {
        (1.0 - self.cos_min) / self.cos_bins as f64
    }

    fn phi_step(&self) -> f64 {
        2.0 * PI / self.phi_bins as f64
    }

    /// The cell of a unit direction, or `None` below `cos_min` (or NaN).
    pub fn cell(&self, w: DVec3) -> Option<usize> {
        if w.z.is_nan() || w.z < self.cos_min {
            return None;
        }
        let c = (((w.z - self.cos_min) / self.cos_step()) as usize).min(self.cos_bins - 1);
        let phi = w.y.atan2(w.x).rem_euclid(2.0 * PI);
        let p = ((phi / self.phi_step()) as usize).min(self.phi_bins - 1);
        Some(c * self.phi_bins + p)
    }

    /// The direction at (cos theta, phi).
    fn direction(c: f64, phi: f64) -> DVec3 {
        let s = (1.0 - c * c).max(0.0).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), c)
    }

    /// The probability of each cell under `pdf` (per steradian), by the midpoint rule on
    /// `k` x `k` points of each cell (d omega = d cos theta d phi).
    pub fn probabilities(&self, pdf: &dyn Fn(DVec3) -> f64, k: usize) -> Vec<f64> {
        let (dc, dp) = (self.cos_step(), self.phi_step());
        (0..self.len())
            .map(|cell| {
                let (c0, p0) = (
                    self.cos_min + (cell / self.phi_bins) as f64 * dc,
                    (cell % self.phi_bins) as f64 * dp,
                );
                let mut sum = 0.0;
                for i in 0..k {
                    for j in 0..k {
                        let c = c0 + (i as f64 + 0.5) * dc / k as f64;
                        let phi = p0 + (j as f64 + 0.5) * dp / k as f64;
                        sum += pdf(Self::direction(c, phi));
                    }
                }
                sum * dc * dp / (k * k) as f64
            })
            .collect()
    }
}

/// The outcome of one test.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Chi2 {
    pub chi2: f64,
    pub dof: usize,
    /// log10 of the p-value: the chance that a sampler of exactly the density would
    /// deviate this much or more.
    pub log10_p: f64,
}

/// Pearson's statistic of the directions `samples` against `probabilities` (per cell of
/// `cells`; the rest of the probability, and samples outside every cell, form one more
/// category). Every category is expected to hold at least 5 samples here.
pub fn chi2(cells: &Cells, samples: &[DVec3], probabilities: &[f64]) -> Chi2 {
    let n = samples.len() as f64;
    let mut observed = vec![0.0f64; cells.len() + 1];
    for &w in samples {
        observed[cells.cell(w).unwrap_or(cells.len())] += 1.0;
    }
    let mut expected: Vec<f64> = probabilities.iter().map(|p| p * n).collect();
    expected.push((n - expected.iter().sum::<f64>()).max(0.0));
    let mut stat = 0.0;
    let mut categories = 0;
    for (o, e) in observed.iter().zip(&expected) {
        if *e > 1e-9 * n {
            stat += (o - e) * (o - e) / e;
            categories += 1;
        } else if *o > 0.0 {
            // Samples where the density has none: as far from it as can be.
            stat = f64::INFINITY;
        }
    }
    let dof = categories - 1;
    Chi2 {
        chi2: stat,
        dof,
        log10_p: ln_gamma_q(0.5 * dof as f64, 0.5 * stat) / std::f64::consts::LN_10,
    }
}
