//! Whether the training run visits every regime of a composed shape's saturating or switching
//! calls: a shape whose regime the run barely enters is not identified by it, and is no candidate.
//!
//! Why: a saturation `clamp(x, lo, hi)` is told from a step only by the rows inside its band, and
//! a relay from a constant only by the rows in each of its states. The composition search moves
//! bounds and switching points freely, and where the evidence of a step or of a few rows is high
//! it settled on shapes the run never resolved (measured on fresh runs: `clamp(rate(t_qma_c,
//! 5900), −0.145, −0.143)`, a band two thousandths wide, tied a mode hop and made "cannot
//! tell"; `supply_v × clamp(supply_v, 28.6, 28.6)` tied the supply; `hyst(lag(supply_v, 3500)
//! − 28.4, 0.2)` and `clamp(lag(supply_v, 5200), 27.5, 27.7)` led negative controls, and the
//! trainer then found them constant).
//!
//! How, without a list of functions: the functions that saturate are told by their behaviour on a
//! test profile, measured once ([`crate::compose`]: a clamp and a relay do; a lag, a rate, a
//! square do not, and their calls cost nothing here). Each such call's output is read on every
//! sample of the training run (what the trainer computes before it bins; a bin's mean input
//! would blur a relay on a fast input's rate out of one of its states), beside its operand.
//! - A *saturation* is an extreme level the output holds while the operand moves over three
//!   values or more: a clamp's bound, a relay's state; not the bottom of `abs` or the top of
//!   `sq`, where the operand stands still or takes the two values that meet there.
//! - When the output has one, each saturation must hold at least [`REGIME_SHARE`] of the
//!   samples, and so must the samples between the levels — unless there are none: then the
//!   output is a switch, and each of its two levels must.
//! - A stateful call's starting state (a relay is 0 until its input first crosses a switching
//!   point) is no regime.
//!
//! [`REGIME_SHARE`] is the share of rows a location's range already leaves beyond each of its ends
//! (the operand's 5th to 95th percentile, [`crate::compose`]).

use tcomp_core::expr::Expr;
use tcomp_core::lang;

/// The smallest share of the rows each regime of a saturating or switching call must hold.
pub const REGIME_SHARE: f64 = 0.05;

/// A call in a composed expression, with its operand.
pub(crate) struct Call {
    pub(crate) call: Expr,
    pub(crate) operand: Expr,
    /// The language's table says it keeps state between samples.
    stateful: bool,
}

impl Call {
    /// Whether the call's output `out` (every sample of the run; `starts`, the first sample of
    /// each stretch) visits each of its regimes on enough samples ([`visited`]). A stateful call
    /// holds its starting state until its input first moves it (`hyst` is 0 before either
    /// switching point is crossed): those samples are no regime, and are left out.
    pub(crate) fn visited(&self, out: &[f64], operand: &[f64], starts: &[usize]) -> bool {
        if !self.stateful {
            return visited(out, operand);
        }
        let mut keep = vec![true; out.len()];
        for (k, &s) in starts.iter().enumerate() {
            let end = starts
                .get(k + 1)
                .copied()
                .unwrap_or(out.len())
                .min(out.len());
            let first = out.get(s).copied();
            for i in s..end {
                if Some(out[i]) != first {
                    break;
                }
                keep[i] = false;
            }
        }
        let pick = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(x, _)| *x)
                .collect()
        };
        visited(&pick(out), &pick(operand))
    }
}

/// The calls in `e` with an operand to a function that `saturates` (by its name), innermost
/// first.
pub(crate) fn calls(e: &Expr, saturates: &dyn Fn(&str) -> bool) -> Vec<Call> {
    let mut out = Vec::new();
    walk(e, saturates, &mut out);
    out
}

fn walk(e: &Expr, saturates: &dyn Fn(&str) -> bool, out: &mut Vec<Call>) {
    match e {
        Expr::Call(name, args) => {
            for a in args {
                walk(a, saturates, out);
            }
            if let Some(x) = args.first()
                && !matches!(x, Expr::Num(..) | Expr::Text(_))
                && saturates(name)
            {
                out.push(Call {
                    call: e.clone(),
                    operand: x.clone(),
                    stateful: lang::function(name).is_some_and(|f| f.stateful),
                });
            }
        }
        Expr::Neg(a) => walk(a, saturates, out),
        Expr::Binary(_, a, b) => {
            walk(a, saturates, out);
            walk(b, saturates, out);
        }
        Expr::Name(_) | Expr::Num(..) | Expr::Text(_) => {}
    }
}

/// Whether `out` holds an extreme level while its `operand` moves ([`level`]).
pub(crate) fn saturates(out: &[f64], operand: &[f64]) -> bool {
    let lo = out.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = out.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    hi > lo && (level(out, operand, lo).1 || level(out, operand, hi).1)
}

/// The rows at level `l`, and whether the operand moves over them (three values or more: the two
/// sides of `abs` or `sq` meet at one level on two values).
fn level(out: &[f64], operand: &[f64], l: f64) -> (usize, bool) {
    let mut xs: Vec<f64> = Vec::new();
    let mut k = 0usize;
    for (o, x) in out.iter().zip(operand) {
        if *o == l {
            k += 1;
            if xs.len() < 3 && !xs.contains(x) {
                xs.push(*x);
            }
        }
    }
    (k, xs.len() >= 3)
}

/// Whether a call's output `out` visits each of its regimes on enough rows, its operand beside it
/// (see the module doc). A constant output, or one without a saturation, passes: those are judged
/// elsewhere.
pub(crate) fn visited(out: &[f64], operand: &[f64]) -> bool {
    let n = out.len();
    if n == 0 || operand.len() != n || out.iter().any(|v| !v.is_finite()) {
        return true;
    }
    let lo = out.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = out.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi <= lo {
        return true;
    }
    let ((at_lo, sat_lo), (at_hi, sat_hi)) = (level(out, operand, lo), level(out, operand, hi));
    if !sat_lo && !sat_hi {
        return true;
    }
    // A function that saturates: each saturation is a regime, and so are the rows between —
    // or, with none between (a switch), each of its two levels.
    let need = (REGIME_SHARE * n as f64).ceil() as usize;
    let between = n - at_lo - at_hi;
    let switch = between == 0;
    let regime = |k: usize, sat: bool| !(sat || switch) || k >= need;
    regime(at_lo, sat_lo) && regime(at_hi, sat_hi) && (switch || between >= need)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clamp(x: &[f64], lo: f64, hi: f64) -> Vec<f64> {
        x.iter().map(|v| v.clamp(lo, hi)).collect()
    }

    /// A ramp up and down, 200 rows from −1 to 1.
    fn ramp() -> Vec<f64> {
        (0..200)
            .map(|i| {
                let u = (i % 100) as f64 / 99.0;
                if i < 100 {
                    2.0 * u - 1.0
                } else {
                    1.0 - 2.0 * u
                }
            })
            .collect()
    }

    #[test]
    fn a_clamp_needs_rows_inside_its_band_and_at_its_bounds() {
        let x = ramp();
        assert!(visited(&clamp(&x, -0.5, 0.5), &x));
        // A band 0.02 wide holds 1 % of the rows: a step, not a saturation.
        assert!(!visited(&clamp(&x, 0.10, 0.12), &x));
        // A bound the run reaches on 2 % of its rows.
        assert!(!visited(&clamp(&x, -0.5, 0.96), &x));
        // A bound it never reaches is no saturation there.
        assert!(visited(&clamp(&x, -0.5, 2.0), &x));
    }

    #[test]
    fn a_switch_needs_rows_in_each_state_and_none_between() {
        let x = ramp();
        let relay =
            |on: f64| -> Vec<f64> { x.iter().map(|v| if *v > on { 1.0 } else { -1.0 }).collect() };
        assert!(visited(&relay(0.0), &x));
        // On in 2 of 200 rows: switched by the run's extreme alone.
        assert!(!visited(&relay(0.97), &x));
    }

    #[test]
    fn a_minimum_where_the_operand_stands_still_is_no_saturation() {
        // `abs` of a quantised operand: many rows at the bottom, the operand the same there.
        let x: Vec<f64> = (0..100)
            .map(|i| ((i as f64 / 10.0).round() - 5.0) / 5.0)
            .collect();
        let a: Vec<f64> = x.iter().map(|v| v.abs()).collect();
        assert!(visited(&a, &x));
        let x = ramp();
        assert!(visited(&x.iter().map(|v| v * v).collect::<Vec<_>>(), &x));
    }

    #[test]
    fn calls_are_listed_innermost_first_those_that_saturate() {
        let rate = Expr::call("rate", [Expr::name("T"), Expr::num(60.0)]);
        let clamp = Expr::call("clamp", [rate, Expr::num(-1.0), Expr::num(1.0)]);
        let e = Expr::call("lag", [clamp, Expr::num(300.0)]) * Expr::name("supply_v");
        let c: Vec<String> = calls(&e, &|_| true)
            .iter()
            .map(|c| c.call.to_string())
            .collect();
        assert_eq!(
            c,
            [
                "rate(T, 60)",
                "clamp(rate(T, 60), -1, 1)",
                "lag(clamp(rate(T, 60), -1, 1), 300)"
            ]
        );
        let c: Vec<String> = calls(&e, &|f| f == "clamp")
            .iter()
            .map(|c| c.call.to_string())
            .collect();
        assert_eq!(c, ["clamp(rate(T, 60), -1, 1)"]);
    }

    #[test]
    fn a_stateful_calls_starting_state_is_no_regime() {
        // A relay that is 0 until its operand first crosses a switching point, then switches.
        let x = ramp();
        let out: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if i < 6 {
                    0.0
                } else if *v > 0.0 {
                    1.0
                } else {
                    -1.0
                }
            })
            .collect();
        assert!(!visited(&out, &x));
        let relay = Call {
            call: Expr::name("r"),
            operand: Expr::name("x"),
            stateful: true,
        };
        assert!(relay.visited(&out, &x, &[0]));
    }
}
