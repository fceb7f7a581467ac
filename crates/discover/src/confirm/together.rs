//! Two effects that explain the run only together, proposed and judged as one candidate.
//!
//! Why: candidates are scored, refitted and judged one at a time against the model as given.
//! When two effects are missing at once and each partly stands in for the other, neither alone is
//! what the run says, and the one named can make the verification run worse. Measured on the
//! `rlg` preset with a model of T alone (its bias: a cubic in T, the rate of T and two thermal
//! gradients): the gradients had the most evidence (+186 nats refitted) but lowered one held-out
//! block of three; the rate of one gradient was named (+144 nats), and the user's fit with it
//! made the verification run 13.7 % worse (0.0676 → 0.0768 deg/h). Each effect alone makes that
//! run worse (the gradients 0.0782, the rate of T 0.0872); the gradients and the rate of the
//! gradient together reach 0.0178, as the true form does (0.0179).
//!
//! How: the leader by the refits' evidence is joined with each of the next [`PARTNERS`] refitted
//! candidates that add columns of their own (no expression shared, neither a refinement nor a
//! replacement of the model's features), and each union is refitted by the trainer on the whole
//! training run. The union with the most evidence is kept when it has at least [`EARN_NATS`] more
//! than either part alone: each part earns its place beside the other (the union of two
//! explanations of one residual gains little over the better one, and is dropped). The union
//! kept is judged as every candidate is — the held-out blocks and their vote, the noise floor —
//! and against placebos of its own ([`crate::placebo`]): each part's columns shifted in time beside
//! the other part's, so that a union is named only when each part explains more beside the other
//! than its shifted copies do. It is never retested in the placebos' second stage (its shifted
//! copy would lose the real part too). One union per diagnosis: [`PARTNERS`] whole-run refits and
//! one set of block refits at most.

use crate::candidates::Searched;
use crate::score::Scored;

/// Candidates after the leader each joined with it.
pub const PARTNERS: usize = 4;

/// Log evidence (nats) a union must gain over each of its parts alone: "strong" on Jeffreys'
/// scale, the criterion's default for a candidate over the model.
pub const EARN_NATS: f64 = 5.0;

/// The refit's Δ log evidence of `c` (−∞ when it was not refitted).
fn refit_gain(c: &Scored) -> f64 {
    c.confirmation
        .as_ref()
        .map_or(f64::NEG_INFINITY, |k| k.delta_log_evidence_refit)
}

/// Whether `c` can be a part: refitted with a finite gain, adding features of its own.
fn joinable(c: &Scored) -> bool {
    let g = refit_gain(c);
    g.is_finite() && g > 0.0 && c.refines.is_none() && c.replaces.is_empty() && c.joined.is_empty()
}

/// The leader of `cands` (by the refits' evidence) joined with each of its partners.
pub(super) fn pairs(cands: &[Scored]) -> Vec<Scored> {
    let mut order: Vec<&Scored> = cands.iter().filter(|c| joinable(c)).collect();
    order.sort_by(|a, b| refit_gain(b).total_cmp(&refit_gain(a)));
    let Some((lead, rest)) = order.split_first() else {
        return Vec::new();
    };
    rest.iter()
        .filter(|b| b.expressions.iter().all(|e| !lead.expressions.contains(e)))
        .take(PARTNERS)
        .map(|b| join(lead, b))
        .collect()
}

/// `a` and `b` as one candidate.
fn join(a: &Scored, b: &Scored) -> Scored {
    let mut u = a.clone();
    u.expressions = a
        .expressions
        .iter()
        .chain(&b.expressions)
        .cloned()
        .collect();
    u.expression = u.expressions.first().cloned().unwrap_or_default();
    u.effect = format!("{}, together with {}", a.effect, b.effect);
    u.parameter = None;
    u.search = None;
    u.searched = Searched::No;
    u.estimate = None;
    u.parameter_scored = None;
    u.members = 1;
    u.confirmation = None;
    u.unconfirmed = None;
    u.placebo = None;
    u.passes = false;
    u.fails.clear();
    u.joined = vec![a.clone(), b.clone()];
    u.ranked = false;
    u
}

/// The union with the most evidence among `unions` (each with its whole-run refit's gain over the
/// model and what else that refit returned), if it gains [`EARN_NATS`] over each of its parts.
pub(super) fn earning<T>(unions: Vec<(Scored, f64, T)>) -> Option<(Scored, f64, T)> {
    unions
        .into_iter()
        .filter(|(u, gain, _)| {
            let parts = u
                .joined
                .iter()
                .map(refit_gain)
                .fold(f64::NEG_INFINITY, f64::max);
            gain.is_finite() && *gain >= parts + EARN_NATS
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::score::refitted;

    /// The leader is joined with the others that add columns of their own, best first; a
    /// refinement, or a candidate sharing the leader's expression, is no partner.
    #[test]
    fn the_leader_joins_the_candidates_that_add_columns_of_their_own() {
        let mut refinement = refitted(&["rate(T, 120)"], 150.0);
        refinement.refines = Some("rate(T)".into());
        let cands = vec![
            refitted(&["rate(a - s)"], 140.0),
            refitted(&["a - s", "c - s"], 186.0),
            refitted(&["a - s"], 170.0),
            refinement,
            refitted(&["lag(T, 300)"], -3.0),
        ];
        let u = pairs(&cands);
        assert_eq!(
            u.len(),
            1,
            "{:?}",
            u.iter().map(|u| &u.expressions).collect::<Vec<_>>()
        );
        assert_eq!(u[0].expressions, ["a - s", "c - s", "rate(a - s)"]);
        assert_eq!(u[0].joined.len(), 2);
        assert!(u[0].effect.contains("together with"), "{}", u[0].effect);
    }

    /// A union is kept only when it gains the threshold over both parts; the best such is kept.
    #[test]
    fn a_union_must_earn_over_each_part() {
        let a = refitted(&["a"], 100.0);
        let b = refitted(&["b"], 90.0);
        let c = refitted(&["c"], 95.0);
        let ab = join(&a, &b);
        let ac = join(&a, &c);
        assert!(earning(vec![(ab.clone(), 104.9, ())]).is_none());
        let kept = earning(vec![(ab, 120.0, ()), (ac, 130.0, ())]).map(|k| k.0.expressions);
        assert_eq!(kept, Some(vec!["a".to_string(), "c".to_string()]));
    }
}
