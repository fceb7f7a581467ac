//! k-means++ with a fixed seed: deterministic RBF centers.
//!
//! Why deterministic: a model must be reproducible from its data and options, and the evidence
//! comparison between settings must not be blurred by random restarts. Seeding is k-means++ driven
//! by a SplitMix64 generator; Lloyd iterations stop when no assignment changes (at most 100).

/// SplitMix64: a tiny, well-mixed deterministic generator.
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// Next value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Squared Euclidean distance.
pub fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// `k` centers of the rows `points` (k-means++ seeding, then Lloyd). Returns fewer than `k` when
/// there are fewer distinct points. Works on flat row-major copies (the search of `bayes` calls it
/// often); the arithmetic is the plain per-row one, so results do not depend on the layout.
pub fn kmeans(points: &[Vec<f64>], k: usize, seed: u64) -> Vec<Vec<f64>> {
    let n = points.len();
    let dim = points.first().map_or(0, Vec::len);
    if k == 0 || n == 0 || dim == 0 {
        return Vec::new();
    }
    let flat: Vec<f64> = points
        .iter()
        .flat_map(|p| (0..dim).map(move |j| p.get(j).copied().unwrap_or(0.0)))
        .collect();
    let row = |i: usize| flat.get(i * dim..(i + 1) * dim).unwrap_or(&[]);
    let mut rng = SplitMix(seed);
    let first = ((rng.next_f64() * n as f64) as usize).min(n - 1);
    let mut centers: Vec<f64> = row(first).to_vec();
    let mut d2: Vec<f64> = (0..n).map(|i| dist2(row(i), row(first))).collect();
    while centers.len() / dim < k {
        let total: f64 = d2.iter().sum();
        if total <= 0.0 {
            break;
        }
        let mut r = rng.next_f64() * total;
        let mut pick = n - 1;
        for (i, d) in d2.iter().enumerate() {
            r -= d;
            if r <= 0.0 {
                pick = i;
                break;
            }
        }
        let c = row(pick).to_vec();
        for (i, d) in d2.iter_mut().enumerate() {
            *d = d.min(dist2(row(i), &c));
        }
        centers.extend_from_slice(&c);
    }
    let kk = centers.len() / dim;
    let mut assign = vec![usize::MAX; n];
    let mut sums = vec![0.0; kk * dim];
    let mut counts = vec![0usize; kk];
    for _ in 0..100 {
        let mut changed = false;
        for (i, a) in assign.iter_mut().enumerate() {
            let p = row(i);
            let mut best = 0;
            let mut bd = f64::INFINITY;
            for (j, c) in centers.chunks_exact(dim).enumerate() {
                let d = dist2(c, p);
                if d < bd {
                    bd = d;
                    best = j;
                }
            }
            if *a != best {
                *a = best;
                changed = true;
            }
        }
        if !changed {
            break;
        }
        sums.fill(0.0);
        counts.fill(0);
        for (i, &a) in assign.iter().enumerate() {
            if let (Some(s), Some(c)) = (sums.get_mut(a * dim..(a + 1) * dim), counts.get_mut(a)) {
                for (sv, pv) in s.iter_mut().zip(row(i)) {
                    *sv += pv;
                }
                *c += 1;
            }
        }
        for ((c, s), &cnt) in centers
            .chunks_exact_mut(dim)
            .zip(sums.chunks_exact(dim))
            .zip(&counts)
        {
            if cnt > 0 {
                for (cv, sv) in c.iter_mut().zip(s) {
                    *cv = sv / cnt as f64;
                }
            }
        }
    }
    centers.chunks_exact(dim).map(<[f64]>::to_vec).collect()
}
