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
/// there are fewer distinct points.
pub fn kmeans(points: &[Vec<f64>], k: usize, seed: u64) -> Vec<Vec<f64>> {
    let n = points.len();
    if k == 0 || n == 0 {
        return Vec::new();
    }
    let mut rng = SplitMix(seed);
    let first = ((rng.next_f64() * n as f64) as usize).min(n - 1);
    let mut centers: Vec<Vec<f64>> = points.get(first).cloned().into_iter().collect();
    let mut d2: Vec<f64> = points
        .iter()
        .map(|p| dist2(p, centers.first().map_or(&[][..], Vec::as_slice)))
        .collect();
    while centers.len() < k {
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
        let Some(c) = points.get(pick).cloned() else {
            break;
        };
        for (d, p) in d2.iter_mut().zip(points) {
            *d = d.min(dist2(p, &c));
        }
        centers.push(c);
    }
    let dim = points.first().map_or(0, Vec::len);
    let mut assign = vec![usize::MAX; n];
    for _ in 0..100 {
        let mut changed = false;
        for (a, p) in assign.iter_mut().zip(points) {
            let best = nearest(&centers, p);
            if *a != best {
                *a = best;
                changed = true;
            }
        }
        if !changed {
            break;
        }
        let mut sums = vec![vec![0.0; dim]; centers.len()];
        let mut counts = vec![0usize; centers.len()];
        for (a, p) in assign.iter().zip(points) {
            if let (Some(s), Some(c)) = (sums.get_mut(*a), counts.get_mut(*a)) {
                for (sv, pv) in s.iter_mut().zip(p) {
                    *sv += pv;
                }
                *c += 1;
            }
        }
        for ((c, s), cnt) in centers.iter_mut().zip(sums).zip(counts) {
            if cnt > 0 {
                *c = s.into_iter().map(|v| v / cnt as f64).collect();
            }
        }
    }
    centers
}

/// Index of the center nearest to `p`.
pub fn nearest(centers: &[Vec<f64>], p: &[f64]) -> usize {
    let mut best = 0;
    let mut bd = f64::INFINITY;
    for (j, c) in centers.iter().enumerate() {
        let d = dist2(c, p);
        if d < bd {
            bd = d;
            best = j;
        }
    }
    best
}
