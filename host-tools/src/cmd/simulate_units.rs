//! `tcomp simulate --preset NAME --units N --outliers K --out DIR`: a production line of `N`
//! simulated units for `tcomp calibrate --units DIR`, each in `DIR/unit-NNNN/` (`train.csv`,
//! `verify.csv`, `truth.json`), with `K` planted outliers listed in `DIR/fleet-truth.json`.
//!
//! Why this spread: units of one design differ a little — each unit's polynomial bias
//! coefficients are the preset's times `1 + 0.05·g` (g standard normal, seeded per unit) and its
//! runs have their own noise seeds. The outliers are planted at fixed, evenly spaced units (so a
//! test knows them without reading anything): every even-numbered outlier has its polynomial
//! coefficients doubled (a coefficient far from the fleet), every odd-numbered one ten times the
//! white noise and bias instability (a held-out residual far from the fleet).

use anyhow::{Context, bail};
use rand::{RngExt as _, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Serialize;
use std::path::Path;
use tcomp_sim::{Effect, Preset, Scenario};

/// Relative spread (1σ) of the polynomial coefficients across units.
pub const COEFF_SPREAD: f64 = 0.05;

/// What was planted in a unit.
#[derive(Clone, Debug, Serialize)]
pub struct Planted {
    /// The unit's folder name.
    pub unit: String,
    /// What is wrong with it.
    pub kind: &'static str,
}

/// `fleet-truth.json`.
#[derive(Serialize)]
struct FleetTruth {
    preset: String,
    units: usize,
    seed: u64,
    coefficient_spread: f64,
    outliers: Vec<Planted>,
}

/// The folder name of unit `i` (0-based).
pub fn unit_name(i: usize) -> String {
    format!("unit-{:04}", i + 1)
}

/// The 0-based indices of `k` outliers spread evenly over `n` units.
pub fn outlier_indices(n: usize, k: usize) -> Vec<usize> {
    (0..k).map(|j| (2 * j + 1) * n / (2 * k)).collect()
}

fn scale_poly(sc: Scenario, factor: f64) -> Scenario {
    let mut sc = sc;
    for e in &mut sc.effects {
        if let Effect::Poly(p) = e {
            for c in &mut p.coefficients {
                *c *= factor;
            }
        }
    }
    sc
}

fn noisy(sc: Scenario, factor: f64) -> Scenario {
    let mut sc = sc;
    sc.noise.white_density *= factor;
    sc.noise.bias_instability *= factor;
    sc
}

/// Writes the fleet; returns the planted outliers.
pub fn run(
    base: &Preset,
    units: usize,
    outliers: usize,
    seed: u64,
    out: &Path,
) -> anyhow::Result<Vec<Planted>> {
    if units == 0 || outliers * 2 > units {
        bail!(
            "--units {units} --outliers {outliers}: give at least one unit and fewer than half as outliers"
        );
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let planted_at = outlier_indices(units, outliers);
    let mut planted = Vec::new();
    let results: Vec<anyhow::Result<Option<Planted>>> = {
        use rayon::prelude::*;
        (0..units)
            .into_par_iter()
            .map(|i| {
                let mut rng = ChaCha8Rng::seed_from_u64(
                    seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
                );
                let g: f64 = rng.sample(StandardNormal);
                let unit_seed = seed.wrapping_add(2 * i as u64);
                let mut p = base
                    .clone()
                    .with_seed(unit_seed)
                    .map(|sc| scale_poly(sc, 1.0 + COEFF_SPREAD * g));
                let kind = planted_at.iter().position(|&j| j == i).map(|n| {
                    if n % 2 == 0 {
                        "coefficients doubled"
                    } else {
                        "noise ×10"
                    }
                });
                match kind {
                    Some("coefficients doubled") => p = p.map(|sc| scale_poly(sc, 2.0)),
                    Some(_) => p = p.map(|sc| noisy(sc, 10.0)),
                    None => {}
                }
                let name = unit_name(i);
                tcomp_sim::write_preset(&p, &out.join(&name), false)?;
                Ok(kind.map(|kind| Planted { unit: name, kind }))
            })
            .collect()
    };
    for r in results {
        if let Some(p) = r? {
            planted.push(p);
        }
    }
    let truth = FleetTruth {
        preset: base.name.clone(),
        units,
        seed,
        coefficient_spread: COEFF_SPREAD,
        outliers: planted.clone(),
    };
    let p = out.join("fleet-truth.json");
    std::fs::write(&p, serde_json::to_string_pretty(&truth)?)
        .with_context(|| format!("writing {}", p.display()))?;
    Ok(planted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outliers_are_spread_and_distinct() {
        assert_eq!(outlier_indices(20, 4), vec![2, 7, 12, 17]);
        let o = outlier_indices(1000, 5);
        assert_eq!(o, vec![100, 300, 500, 700, 900]);
    }
}
