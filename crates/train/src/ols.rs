//! Orthogonal least squares forward selection of RBF centers (Chen, Cowan and Grant, 1991): the
//! other way the seed papers' "traditional" RBF picks its centers.
//!
//! Why: k-means puts centers where the *data* are dense, whatever the target does; OLS puts them
//! where they explain the most *error*. Every training row is a candidate center (with one common
//! width); the regressors are orthogonalised, by modified Gram–Schmidt, against the bias and the
//! centers already chosen, and each step takes the candidate with the largest error reduction ratio
//! `ERR_k = (w_kᵀy)² / (w_kᵀw_k · yᵀy)`. Because the models are nested, the training error never
//! rises as centers are added. Weights are then refitted by least squares on the chosen centers.
//!
//! Cost: O(N·K·M) for N rows, K candidates and M centers, and N·K doubles of memory; candidates
//! are thinned evenly to [`MAX_CANDIDATES`] when there are more rows (only without averaging).

/// Candidate centers at most (evenly spaced rows beyond that).
pub const MAX_CANDIDATES: usize = 400;

/// The rows of `n` that are candidate centers: all of them, or [`MAX_CANDIDATES`] evenly spaced.
pub fn candidate_rows(n: usize) -> Vec<usize> {
    (0..n).step_by(n.div_ceil(MAX_CANDIDATES).max(1)).collect()
}

/// Indices into `z` of up to `m` centers chosen by forward selection for targets `y`, with the
/// Gaussian width `sigma` (in the units of `z`). Stops early when no candidate is left that is not
/// (numerically) a combination of those chosen, or when the residual is exhausted.
pub fn select(z: &[Vec<f64>], y: &[f64], m: usize, sigma: f64) -> Vec<usize> {
    let n = z.len().min(y.len());
    if n == 0 || m == 0 {
        return Vec::new();
    }
    let candidates = candidate_rows(n);
    let half_inv_s2 = 0.5 / (sigma * sigma);
    // Column k: the Gaussian of candidate k over every row, made orthogonal to the bias.
    let mut cols: Vec<Vec<f64>> = candidates
        .iter()
        .map(|&c| {
            let center = &z[c];
            let mut col: Vec<f64> = z
                .iter()
                .take(n)
                .map(|r| (-half_inv_s2 * crate::kmeans::dist2(r, center)).exp())
                .collect();
            let mean = col.iter().sum::<f64>() / n as f64;
            col.iter_mut().for_each(|v| *v -= mean);
            col
        })
        .collect();
    let norms0: Vec<f64> = cols.iter().map(|c| dot(c, c)).collect();
    let ymean = y.iter().take(n).sum::<f64>() / n as f64;
    let mut r: Vec<f64> = y.iter().take(n).map(|v| v - ymean).collect();
    let yy = dot(&r, &r);
    let mut chosen = Vec::new();
    let mut alive = vec![true; cols.len()];
    while chosen.len() < m && yy > 0.0 {
        let mut best: Option<(usize, f64)> = None;
        for (k, col) in cols.iter().enumerate() {
            let Some(true) = alive.get(k) else {
                continue;
            };
            let ww = dot(col, col);
            // What is left of this candidate is rounding: it adds nothing new.
            if ww <= 1e-10 * norms0.get(k).copied().unwrap_or(0.0) || ww <= 0.0 {
                continue;
            }
            let g = dot(col, &r);
            let err = g * g / (ww * yy);
            if best.is_none_or(|(_, e)| err > e) {
                best = Some((k, err));
            }
        }
        let Some((k, err)) = best else {
            break;
        };
        if err <= 1e-14 {
            break;
        }
        if let Some(a) = alive.get_mut(k) {
            *a = false;
        }
        chosen.push(candidates.get(k).copied().unwrap_or(0));
        let q = cols.get(k).cloned().unwrap_or_default();
        let qq = dot(&q, &q);
        // The residual and every remaining candidate lose their component along q.
        let a = dot(&q, &r) / qq;
        r.iter_mut().zip(&q).for_each(|(v, qv)| *v -= a * qv);
        for (j, col) in cols.iter_mut().enumerate() {
            if alive.get(j) == Some(&true) {
                let a = dot(&q, col) / qq;
                col.iter_mut().zip(&q).for_each(|(v, qv)| *v -= a * qv);
            }
        }
    }
    chosen
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows() -> Vec<Vec<f64>> {
        (0..120).map(|i| vec![i as f64 * 0.05]).collect()
    }

    #[test]
    fn recovers_the_centers_a_target_is_made_of() {
        let z = rows();
        let sigma = 0.3;
        let truth = [(17usize, 1.0), (60, -0.7), (101, 0.5)];
        let g = |a: &[f64], b: &[f64]| (-crate::kmeans::dist2(a, b) / (2.0 * sigma * sigma)).exp();
        let y: Vec<f64> = z
            .iter()
            .map(|r| 0.2 + truth.iter().map(|&(c, w)| w * g(r, &z[c])).sum::<f64>())
            .collect();
        let mut picked = select(&z, &y, 3, sigma);
        picked.sort_unstable();
        assert_eq!(picked, vec![17, 60, 101]);
    }

    #[test]
    fn stops_when_the_target_is_explained() {
        // A constant target is all bias: nothing for a center to explain.
        let z = rows();
        let y = vec![3.0; z.len()];
        assert!(select(&z, &y, 5, 0.3).is_empty());
    }

    #[test]
    fn chosen_centers_are_distinct_rows() {
        let z = rows();
        let y: Vec<f64> = z.iter().map(|r| (3.0 * r[0]).sin()).collect();
        let p = select(&z, &y, 20, 0.2);
        assert_eq!(p.len(), 20);
        let mut s = p.clone();
        s.sort_unstable();
        s.dedup();
        assert_eq!(s.len(), 20);
    }
}
