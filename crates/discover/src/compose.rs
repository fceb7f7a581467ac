//! Candidates composed from the feature language: every function of the language applied to every
//! input, then again to the best of those, with every parameter estimated — so that an effect
//! nobody wrote a family for (a relay on a shifted temperature, the rate of a lagged input, an
//! input times a rate) is still searched.
//!
//! Why: the families of [`crate::candidates`] are the shapes someone thought of. A hidden set made
//! of new compositions (a mode hop that switches at one temperature on heating and another on
//! cooling, a supply voltage acting through a lag) was named as the nearest listed shape. Here the
//! shapes come from [`tcomp_core::lang::FUNCTIONS`] itself: a function added to the language is
//! composed with everything else without editing this module.
//!
//! How:
//! - **Atoms**: the sensor's temperatures (the model's signals and thermometer columns), the
//!   differences of thermometer pairs (gradients), the non-thermal inputs, and the language's
//!   functions of time alone (`warmup(τ)`). Never the chamber's air or another inertial output
//!   ([`Sources`] sorted them out).
//! - **Operators**: every function with one operand, and the product with an atom.
//! - **Parameters** get their range from what they are, read from the language's table and the
//!   operand's data — not from a list per function: a parameter in seconds (`tau_s`, `window_s`)
//!   spans half a bin to a third of the run, log-spaced; a non-negative threshold spans 1 % to
//!   50 % of the operand's spread, log-spaced; a location (`clamp`'s bounds, a shift) spans the
//!   operand's 5th to 95th percentile.
//! - **A shift** `x − c`, `c` estimated, is put in front of a *level* operand (a temperature, a
//!   voltage, a gradient: where its zero lies says nothing about where an effect switches) when the function depends on where zero is: tested
//!   numerically, once per function, by whether `f(x − c)` lies in the span of `f(x)`, `x` and 1
//!   (`lag` and `rate` are not shifted; `sq` is shifted only where `x` is no term of the model,
//!   whose linear terms would otherwise absorb what a shift changes). A function with a location
//!   parameter of its own (`clamp`) is not shifted either.
//!   That is how `hyst(T − c, h)` — a bias that switches at `c + h` on heating and `c − h` on
//!   cooling — arises without being listed.
//! - **Scored cheaply first**: each composition's column against the base design's residual by the
//!   sparse-Bayesian increment of Tipping and Faul (2003): the gain in log evidence of adding one
//!   column at its best prior precision, the base's hyperparameters held — closed-form, no refit.
//!   Each shape's parameters are searched on a coarse grid on the bins' mean rows; the coarse
//!   leaders are re-scored on every row (a bin mean smooths a noisy input before a relay sees
//!   it) and the best refined by golden-section sweeps ([`crate::param::golden`]). Before that,
//!   each place of a shape's best grid point (a switching point, a bound, a shift) is scanned
//!   across its whole range on a finer line ([`LINE`] positions), the others held: the evidence
//!   is peaked in a place more narrowly than the grid's step and flat between the operand's
//!   values, where golden-section search cannot tell which way to go.
//! - **Parameters estimated jointly**: a depth-two shape keeps its inner shape's parameters
//!   free. Its grid holds them at the inner estimate and a quarter of their range either way,
//!   beside a coarse grid over all its parameters together, and the refinement sweeps them with
//!   the outer ones: the lag that best explains the residual alone is not the lag in front of a
//!   rate or a relay (measured: `rate(lag(supply_v, 600))` was named `supply_v` and then `cannot
//!   tell`, 7.5× the floor, with the inner lag held; found as `lag(rate(supply_v, 64), 480)`,
//!   1.41×, with it free), and a relay alone switches at other points than a relay in front of a
//!   lag (`lag(hyst(supply_v − 28.2, 0.2), 600)` was named `lag(clamp(supply_v, 27.9, 28.4),
//!   580)`, 1.98× the floor, from the starts around the relay alone's wider band, 28.4 ± 0.65;
//!   found exactly, 1.01×, with the joint grid). The joint grid is laid where the inner shape
//!   has two parameters or more (one inner parameter is reached from the starts) and the whole
//!   shape at most [`JOINT_PARAMS`] (8 positions each).
//! - **One shape, one name**: the language's linear time-invariant filters (measured like the
//!   shift: `f(3x) = 3 f(x)` and `f(x + c) − f(x)` constant; `lag` and `rate`) commute, so a chain
//!   of them is one shape in any order ([`signature`]).
//!
//! Pruned by physics: depth two at most; a function is not applied to its own output unless it
//! passes a level through (`abs(abs(x))`, `clamp(clamp(x))` add nothing; two lags in series are a
//! second-order path); a shift only where the function depends on it; and no memoryless function
//! (the language's table says which are stateless) of temperatures alone: a kink, a saturation or
//! a square in temperature is a shape of the bias–temperature curve, which the model's own terms
//! in temperature fit — not a missing signal (measured: with them, a drifting run with a case
//! thermometer got `abs(t_case_c + 28)` and `clamp(t_case_c, 37.4, 48.8)` named, 2 of 20 fresh
//! seeds, and a lag hidden in a gappy log was named as a kink of the lag). A temperature's rate
//! is not a temperature, though: memoryless functions of a rate are composed (`abs(rate(T))`, a
//! bias the same on heating and cooling, was pruned as a curve shape and missed, 7.2× the floor).
//! Pruned by the run: a shape whose saturation or switch the training run barely enters (a clamp's
//! band, a relay's state held on fewer than 5 % of the samples: [`crate::regimes`]) is not
//! identified by it, and has no gain on every row — the re-scoring and the refinement pass it by
//! (measured: a clamp of a rate to a band two thousandths wide tied a mode hop and made "cannot
//! tell"; on fresh negative controls, a clamp of an idle heater's rate to a band 0.0002 wide was
//! named, 1 of 100, and is no longer).
//! Pruned by evidence: only the [`BEAM`] best depth-one shapes are composed again — and beside them
//! the [`PER_OPERAND`] best over each non-thermal input, so that one input's shapes (or an idle
//! column's) cannot fill the beam alone (measured: `lag(abs(supply_v − 28.1), 900)` was never
//! composed, `abs(supply_v − 28.1)` seventh behind a relay on the supply and four shapes of an idle
//! heater column; with it, the lag of it led the depth-two search by 77 nats). A rate the beam
//! leaves out is still composed with the even functions (those that forget their operand's sign,
//! measured like every behaviour: the square, the size): an even function of a rate has no linear
//! part in it, so the rate's own gain cannot nominate it (measured: `sq(rate(t_anode_c −
//! t_shell_c))` was never composed, the gradient's rate 36th at depth one; with it, named exactly).
//! A composition is kept when it explains more than the best single shape by [`EARN_NATS`], or as
//! much as it (within [`crate::score::INDISTINCT_NATS`]) and more than its own inner shape by
//! [`EARN_NATS`]: another explanation of the same residual, for the refits and the verdict to weigh
//! (measured: a relay on a lagging element tied a wider relay on the thermometer, 111.1 against
//! 110.9 nats, and the wider relay was named, 1.85× the floor where the truth reaches 0.91×; handed
//! on, the two are weighed by the verdict, whose structure prior names the simpler where the refits
//! tie: [`crate::description`]). Shapes whose training columns are one ([`simplest`]: the same
//! column, the same stateful functions over the same inputs) are one name, the simplest. Only the
//! [`PROPOSED`] best shapes that no listed family already covers are handed on. They are then
//! scored, refitted, placebo-tested — each placebo the best of the same shape's members on the
//! shifted columns ([`crate::candidates::Searched::Alternatives`]), since the candidate is the best
//! of them on the run — and judged like every other candidate, including the leg that the trainer's
//! refit with a candidate read off the data must gain evidence ([`crate::verdict`]). The choice
//! among the shapes is priced too: each of the `N` shapes searched holds `1/N` of the prior a
//! listed family holds, so a composition's placebo statistic is lowered by `ln N` nats
//! ([`crate::placebo`]).
//!
//! Measured (`tests/composed.rs`, `tests/false_discoveries.rs`, BENCHMARKS.md): a mode hop, a
//! relay on a supply voltage or on a gradient away from zero, a lagged relay and a V-shaped
//! supply are named with their parameters exactly; the rate of a lagged input as a lagged rate,
//! the size of a temperature's rate or a supply's, the rate of a saturating supply, a lagged
//! V-shaped supply, a kink in a lagged supply, a lagged saturating supply, a lagged heater
//! voltage (`lag(heater_v, 700)`), the square of a gradient's rate.
//! Not yet: a mode hop of a lagging element (a wider relay ties it, below), an input times a rate,
//! a lagged rate (named as the lag it equals with the model's own `T`), a narrow mode hop, a
//! saturating gradient, a saturating lagging element, a lagged mode hop, a lagged warm-up (named as
//! one warm-up); a saturating supply (named as a kink's clamp whose bounds the run prefers to the
//! truth's), a relay on a heater that steps between levels (any switching point between two of them
//! is the same training column), a relay on a lagged supply ("cannot tell": its held-out refits
//! disagree), a relay on the supply times the temperature (the shape named, a switching point 0.1 V
//! off, which the verification run magnifies) or times its rate, a relay on a lagged gradient
//! (named with its lag 1.5× the truth's), and a kink in a second input (named through a short lag
//! of it).
//!
//! Places are written to the run's precision (`plainest`, below): the shortest number whose
//! gain the run cannot tell from the estimate's. A relay's switching points are otherwise
//! estimated to a hundredth of a degree the run does not pin, and printed to significant figures
//! of their own size they land on a grid as coarse as 1 °C (measured: a mode hop at 30 and 10 °C
//! was named through a 94 s lag on three runs of four, 3.5× the floor; with places written to
//! the run's precision it is named exactly on one of them too, 1.02×, and on the other two the
//! search of the relay alone still stopped at a falling point of 8.1 °C — the line scan of each
//! place finds 10 °C). The line scan also finds the wider relay that a relay through a lag
//! equals on a run with one ramp rate: a mode hop of a lagging element ties it (112.2 against
//! 112.0 nats) and is then named as the wider relay by the structure prior.

use crate::base::Prepared;
use crate::candidates::{Candidate, EffectKind, Family, Searched, Sources};
use crate::param::significant;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::sync::Mutex;
use tcomp_core::expr::{BinOp, Expr};
use tcomp_core::lang::{self, Domain, Function, Operands};
use tcomp_train::Dataset;
use tcomp_train::features::{self, FeatureSpec};

/// Depth-one shapes composed again (and depth-two shapes kept). Eight, not six, since a shifted
/// square of a supply took a place: `hyst(lag(supply_v, 300) − 28.2, 0.15)` was then not
/// composed, as `lag(supply_v)` came seventh (measured: `tcomp diagnose` on the RLG preset's
/// 22,000 rows 1.39–1.45 s with eight, under the 2 s budget).
pub const BEAM: usize = 8;
/// Depth-one shapes of each operand composed again beside the beam.
pub const PER_OPERAND: usize = 2;
/// Composed candidates handed on to scoring.
pub const PROPOSED: usize = 4;
/// How many times the beam's width of the coarse screen's best shapes are re-scored on every row.
const RESCORED: usize = 3;
/// Nats a depth-two composition must gain over the best depth-one shape (odds of about 20 : 1).
const EARN_NATS: f64 = 3.0;
/// Golden-section steps per parameter and sweep of the refinement.
const REFINE_STEPS: usize = 7;
/// Sweeps of the refinement (one parameter at a time).
const SWEEPS: usize = 2;
/// Sweeps of a depth-two shape's refinement: its inner parameters start where the inner shape
/// alone was best and may have further to go.
const JOINT_SWEEPS: usize = 4;

/// What a parameter is, which sets its range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// A time in seconds (the language names them `*_s`).
    Time,
    /// A non-negative size on the operand's scale (a threshold).
    Threshold,
    /// A place on the operand's scale (a bound, a shift).
    Location,
}

/// A parameter's range; log-spaced unless a location.
#[derive(Clone, Copy, Debug)]
struct Range {
    lo: f64,
    hi: f64,
    role: Role,
}

impl Range {
    /// The value at `u` ∈ [0, 1] across the range.
    fn at(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        match self.role {
            Role::Location => self.lo + (self.hi - self.lo) * u,
            _ => self.lo * (self.hi / self.lo).powf(u),
        }
    }

    /// The value as printed: two significant figures for a size; a place to the decade below a
    /// [`LOCATION_STEPS`]th of the range, its operand's spread — not to significant figures of
    /// its own size, which put a switching point 10 °C from zero on a grid of 0.1 °C and one
    /// 30 °C away on 1 °C (measured: a mode hop at 30 °C rising and 10 °C falling could be
    /// written only as 30.9 and 8.9, 4.3 nats below the truth, and a relay through a 94 s lag
    /// was named instead: 3.5× the floor on the verification run, where the truth reaches 1.02×).
    fn rounded(&self, v: f64) -> f64 {
        match self.role {
            Role::Location => to_decimals(v, self.decimals()),
            _ => significant(v, 2),
        }
    }

    /// Decimals a place on this range is printed to.
    fn decimals(&self) -> usize {
        let step = (self.hi - self.lo).abs() / LOCATION_STEPS;
        if step.is_finite() && step > 0.0 {
            (-step.log10().floor()).clamp(0.0, 12.0) as usize
        } else {
            3
        }
    }
}

/// A place (a shift, a bound, a switching point) is printed to the decade below this fraction of
/// its operand's spread: 0.1 °C on a run spanning 90 °C, 1 mV on a supply wandering 0.8 V.
const LOCATION_STEPS: f64 = 200.0;

/// `v` to `d` decimals, through its decimal text (so that it prints as written).
fn to_decimals(v: f64, d: usize) -> f64 {
    if !v.is_finite() {
        return v;
    }
    format!("{v:.d$}").parse().unwrap_or(v)
}

/// An input the compositions start from.
#[derive(Clone, Debug)]
struct Atom {
    expr: Expr,
    /// Where its zero lies says nothing about where its effects switch or bend (a temperature, a
    /// voltage, a gradient): a shift `x − c` is searched in front of the functions whose output
    /// depends on it.
    level: bool,
}

/// The operator a shape applies.
#[derive(Clone, Debug)]
enum Op {
    /// A function of the language.
    Call(&'static Function),
    /// The product with an atom.
    Times(Expr),
}

/// A composition: `op` applied to `operand` (an atom, or a depth-one shape). At depth two the
/// inner shape's parameters stay free too ([`Shape::inner`]), so that they are re-estimated with
/// the outer ones: the lag that best explains the residual alone is not the lag in front of a
/// relay, a rate or a product.
#[derive(Clone, Debug)]
struct Shape {
    /// The operand at the inner shape's estimate (at depth one, the atom).
    operand: Option<Expr>,
    /// At depth two, the inner shape and its estimate: its parameters come first in a position
    /// vector, the outer shape's after them.
    inner: Option<Box<Found>>,
    op: Op,
    /// A shift `operand − c` is estimated (the first parameter).
    shifted: bool,
    /// The shift and the threshold that follows it are searched as two switching points on the
    /// operand's scale, upper and lower (a relay's evidence is peaked in each of them apart;
    /// in the shift and the half-width it lies along a diagonal ridge).
    switching: bool,
    ranges: Vec<Range>,
    /// The operand is a level (see [`Atom::level`]).
    level: bool,
}

impl Shape {
    /// Parameters searched: the inner shape's, then this one's ranges.
    fn params(&self) -> usize {
        self.inner.as_ref().map_or(0, |f| f.shape.params()) + self.ranges.len()
    }

    /// The range of parameter `j` (the inner shape's first, then this one's).
    fn range_at(&self, j: usize) -> Option<Range> {
        let k = self.inner.as_ref().map_or(0, |f| f.shape.params());
        match &self.inner {
            Some(f) if j < k => f.shape.range_at(j),
            _ => self.ranges.get(j - k).copied(),
        }
    }

    /// The other switching point of the relay whose point parameter `j` is, if it is one.
    fn partner(&self, j: usize) -> Option<usize> {
        let k = self.inner.as_ref().map_or(0, |f| f.shape.params());
        match &self.inner {
            Some(f) if j < k => f.shape.partner(j),
            _ if self.switching && j == k => Some(k + 1),
            _ if self.switching && j == k + 1 => Some(k),
            _ => None,
        }
    }

    /// The refinement's step per parameter: a grid step of the level the parameter belongs to.
    fn steps(&self) -> Vec<f64> {
        let mut out = self.inner.as_ref().map_or(Vec::new(), |f| f.shape.steps());
        let own = 1.0 / per_param(self.ranges.len()) as f64;
        out.extend(std::iter::repeat_n(own, self.ranges.len()));
        out
    }

    /// The expression at parameter values `v` (the inner shape's, then one per range).
    fn build(&self, v: &[f64]) -> Expr {
        let (operand, v) = match &self.inner {
            Some(f) => {
                let k = f.shape.params().min(v.len());
                (Some(f.shape.build(&v[..k])), &v[k..])
            }
            None => (self.operand.clone(), v),
        };
        let mut all: Vec<f64> = self
            .ranges
            .iter()
            .zip(v)
            .map(|(r, &x)| r.rounded(r.at(x)))
            .collect();
        if self.switching {
            // Two switching points, upper and lower, as the shift and the threshold around it:
            // each point printed as a place, their middle and half-distance to one decimal more,
            // so that `c ± h` gives the points back exactly.
            if let (Some(&a), Some(&b), Some(r)) = (all.first(), all.get(1), self.ranges.first()) {
                let (hi, lo) = (a.max(b), a.min(b));
                let d = r.decimals() + 1;
                all[0] = to_decimals((hi + lo) / 2.0, d);
                all[1] = to_decimals((hi - lo) / 2.0, d);
            }
        }
        let mut vals = all.into_iter();
        match &self.op {
            Op::Times(a) => a.clone() * operand.unwrap_or(Expr::num(1.0)),
            Op::Call(f) => {
                let mut args = Vec::new();
                if let Some(x) = &operand {
                    let x = if self.shifted {
                        let c = vals.next().unwrap_or(0.0);
                        if c < 0.0 {
                            x.clone() + Expr::num(-c)
                        } else {
                            x.clone() - Expr::num(c)
                        }
                    } else {
                        x.clone()
                    };
                    args.push(x);
                }
                let mut prev = f64::NEG_INFINITY;
                for p in f.params {
                    let mut v = vals.next().unwrap_or(f64::from(p.default.unwrap_or(1.0)));
                    if p.domain == Domain::NotBelowPrevious {
                        v = v.max(prev);
                    }
                    prev = v;
                    args.push(Expr::num(v));
                }
                Expr::call(f.name, args)
            }
        }
    }
}

/// What a function does to a level, read off the language's own evaluator once per function.
#[derive(Clone, Copy, Debug)]
struct Behaviour {
    /// `f(x − c)` is not in the span of `f(x)`, `x` and 1: where zero is matters.
    shift_matters: bool,
    /// `f(x − c)` is not in the span of `f(x)` and 1: where zero is matters unless `x` itself is
    /// in the model (a square).
    shift_matters_alone: bool,
    /// `f(x + c) = f(x) + c`: the output is a level too (a lag).
    keeps_level: bool,
    /// `f(a·x + c) = a·f(x) + f(c)`: a linear time-invariant filter (a lag, a rate), which
    /// commutes with any other: `lag(rate(x))` and `rate(lag(x))` are one shape.
    linear: bool,
    /// The output holds a level while the operand moves (a clamp's bound, a relay's state): the
    /// run must visit each of its regimes ([`crate::regimes`]).
    saturates: bool,
    /// `f(−x) = f(x)`: the output forgets the operand's sign (a square, a size).
    even: bool,
}

/// Every one-operand function of the language with its behaviour, measured once per process.
fn behaviours() -> &'static [(&'static Function, Behaviour)] {
    static ALL: std::sync::OnceLock<Vec<(&'static Function, Behaviour)>> =
        std::sync::OnceLock::new();
    ALL.get_or_init(|| {
        lang::FUNCTIONS
            .iter()
            .filter_map(|f| behaviour(f).map(|b| (f, b)))
            .collect()
    })
}

/// A smooth up-and-down test profile and its shifted copy, through `f` at mid-range parameters.
fn behaviour(f: &Function) -> Option<Behaviour> {
    if f.operands != Operands::One {
        return None;
    }
    let n = 3000;
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64;
            20.0 + 30.0 * (std::f64::consts::TAU * t / 1500.0).sin() + 5.0 * (t / 370.0).cos()
        })
        .collect();
    let params = |_: ()| -> Vec<Expr> {
        let mut prev = f64::NEG_INFINITY;
        f.params
            .iter()
            .map(|p| {
                let v = if p.name.ends_with("_s") {
                    100.0
                } else {
                    match p.domain {
                        Domain::NonNegative | Domain::Positive => 5.0,
                        Domain::Finite => 0.0,
                        Domain::NotBelowPrevious => prev.max(0.0) + 30.0,
                    }
                };
                prev = v;
                Expr::num(v)
            })
            .collect()
    };
    let call = |x: Expr| Expr::call(f.name, std::iter::once(x).chain(params(())));
    let exprs = [
        call(Expr::name("x")).to_string(),
        call(Expr::name("x") - Expr::num(10.0)).to_string(),
        call(Expr::name("x") + Expr::num(10.0)).to_string(),
        call(Expr::num(3.0) * Expr::name("x")).to_string(),
        call(-Expr::name("x")).to_string(),
    ];
    let time: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let data = Dataset::from_columns(
        "composition test",
        vec!["time_s".into(), "x".into()],
        vec![time.clone(), x.clone()],
    );
    let spec = FeatureSpec {
        signals: Vec::new(),
        features: exprs.to_vec(),
    };
    let program = spec.program().ok()?;
    let rows = features::compute(&program, &data, &time, &[0]).ok()?;
    let col = |k: usize| -> Vec<f64> { rows.iter().map(|r| f64::from(r[k])).collect() };
    let (fx, fs, fp, f3, fm) = (col(0), col(1), col(2), col(3), col(4));
    let unexplained = unexplained(&fs, &[&fx, &x]);
    let scale = fx.iter().map(|v| v.abs()).fold(0.0, f64::max).max(1e-9);
    let keeps = fp
        .iter()
        .zip(&fx)
        .all(|(a, b)| ((a - b) - 10.0).abs() <= 1e-3 * (scale + 10.0));
    let tol = 1e-3 * (scale + 10.0);
    let steps: Vec<f64> = fp.iter().zip(&fx).map(|(a, b)| a - b).collect();
    let (lo, hi) = steps
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    let scales = f3
        .iter()
        .zip(&fx)
        .all(|(a, b)| (a - 3.0 * b).abs() <= 3.0 * tol);
    let alone = self::unexplained(&fs, &[&fx]);
    let even = fm.iter().zip(&fx).all(|(a, b)| (a - b).abs() <= tol);
    Some(Behaviour {
        shift_matters: unexplained > 1e-4,
        shift_matters_alone: alone > 1e-4,
        keeps_level: keeps,
        linear: scales && hi - lo <= tol,
        saturates: crate::regimes::saturates(&fx, &x),
        even,
    })
}

/// 1 − R² of `y` on `xs` and a constant (least squares).
fn unexplained(y: &[f64], xs: &[&Vec<f64>]) -> f64 {
    let n = y.len();
    let m = xs.len() + 1;
    let a = DMatrix::from_fn(n, m, |i, j| {
        if j == 0 {
            1.0
        } else {
            xs.get(j - 1).and_then(|c| c.get(i)).copied().unwrap_or(0.0)
        }
    });
    let yv = DVector::from_column_slice(y);
    let g = a.tr_mul(&a) + DMatrix::identity(m, m) * 1e-9;
    let Some(ch) = g.cholesky() else { return 1.0 };
    let b = ch.solve(&a.tr_mul(&yv));
    let r = &yv - &a * b;
    let mean = y.iter().sum::<f64>() / n.max(1) as f64;
    let ss: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    if ss <= 1e-300 {
        return 0.0;
    }
    r.dot(&r) / ss
}

/// The cheap score: Tipping and Faul's increment of the log evidence for adding one column to the
/// base design at its best prior precision, the base's hyperparameters held.
struct Screen<'a> {
    p: &'a Prepared,
    /// The training run one row per bin (the coarse grid's columns).
    rows: Dataset,
    /// Residual of the base posterior mean.
    r: DVector<f64>,
    /// Posterior covariance of the base weights.
    cov: DMatrix<f64>,
    beta: f64,
    /// The coarse screen's gain of every expression scored so far, by its text: parameters are
    /// rounded to the figures they print with, so a grid point, a refinement's probe and another
    /// shape's inner start often spell the same expression (the same column, the same gain).
    coarse_seen: Mutex<HashMap<String, f64>>,
    /// Whether the run visits every regime of an expression's calls ([`crate::regimes`]), by its
    /// text.
    regimes_seen: Mutex<HashMap<String, bool>>,
}

impl<'a> Screen<'a> {
    fn new(p: &'a Prepared) -> Option<Self> {
        let phi = &p.phi;
        let beta = p.base.beta;
        let m = phi.ncols();
        let mut a = phi.tr_mul(phi) * beta;
        for j in 0..m {
            let g = p.groups.get(j).copied().unwrap_or(0);
            let alpha = p.base.alpha.get(g).copied().unwrap_or(0.0);
            a[(j, j)] += alpha.max(1e-12);
        }
        let cov = a.try_inverse()?;
        let r = &p.y - phi * &p.base.w;
        Some(Screen {
            p,
            rows: p.bin_rows(),
            r,
            cov,
            beta,
            coarse_seen: Mutex::new(HashMap::new()),
            regimes_seen: Mutex::new(HashMap::new()),
        })
    }

    /// The gain of `e` computed on every row (nats; −∞ when its column cannot be computed or is
    /// constant, or when the run does not visit every regime of its calls: see
    /// [`Screen::regimes_and_column`]).
    fn gain(&self, e: &Expr) -> f64 {
        let text = e.to_string();
        let (visited, col) = match self.regimes_known(&text) {
            Some(v) => (v, None),
            None => self.regimes_and_column(e, &text),
        };
        if !visited {
            return f64::NEG_INFINITY;
        }
        let col = col.unwrap_or_else(|| {
            self.p
                .binned(&[text])
                .map(|c| c.into_iter().next().unwrap_or_default())
        });
        col.map_or(f64::NEG_INFINITY, |c| self.gain_of(c))
    }

    /// The gain of `e` computed on the bins' mean rows: a coarse grid's screen.
    fn gain_coarse(&self, e: &Expr) -> f64 {
        let text = e.to_string();
        let seen = self
            .coarse_seen
            .lock()
            .ok()
            .and_then(|m| m.get(&text).copied());
        if let Some(g) = seen {
            return g;
        }
        let g = self.gain_coarse_of(text.clone());
        if let Ok(mut m) = self.coarse_seen.lock() {
            m.insert(text, g);
        }
        g
    }

    /// Whether the run visits every regime of the expression spelled `text`, when already judged.
    fn regimes_known(&self, text: &str) -> Option<bool> {
        self.regimes_seen
            .lock()
            .ok()
            .and_then(|m| m.get(text).copied())
    }

    /// Whether the training run's samples visit every regime of `e`'s saturating or switching
    /// calls ([`crate::regimes`]), kept by its text: a shape that fails has no gain on every row,
    /// so that the re-scoring and the refinement pass it by. (The coarse screen does not judge it:
    /// a bin's mean input blurs a relay on a fast input's rate out of one of its states.) With
    /// it, `e`'s binned column when it was computed in the same pass
    /// ([`Prepared::per_sample_and_binned`]).
    fn regimes_and_column(
        &self,
        e: &Expr,
        text: &str,
    ) -> (bool, Option<crate::error::Result<Vec<f64>>>) {
        let calls = crate::regimes::calls(e, &|name| {
            behaviours()
                .iter()
                .any(|(f, b)| f.name == name && b.saturates)
        });
        let (v, col) = if calls.is_empty() {
            (true, None)
        } else {
            let features: Vec<String> = calls
                .iter()
                .flat_map(|c| [c.call.to_string(), c.operand.to_string()])
                .collect();
            let starts = self.p.stretch_starts();
            let (cols, col) = self.p.per_sample_and_binned(&features, text);
            let v = cols.map_or(true, |cols| {
                cols.chunks(2)
                    .zip(&calls)
                    .all(|(pair, c)| c.visited(&pair[0], &pair[1], starts))
            });
            (v, Some(col))
        };
        if let Ok(mut m) = self.regimes_seen.lock() {
            m.insert(text.to_string(), v);
        }
        (v, col)
    }

    /// [`Screen::gain_coarse`] computed.
    fn gain_coarse_of(&self, text: String) -> f64 {
        let spec = FeatureSpec {
            signals: self.p.signals().to_vec(),
            features: vec![text],
        };
        let Ok(program) = spec.program() else {
            return f64::NEG_INFINITY;
        };
        let Ok(time) = self.rows.time(self.p.time_name()) else {
            return f64::NEG_INFINITY;
        };
        let Ok(rows) = features::compute(&program, &self.rows, time, &[0]) else {
            return f64::NEG_INFINITY;
        };
        self.gain_of(rows.iter().map(|r| f64::from(r[0])).collect())
    }

    /// The gain of one binned column.
    fn gain_of(&self, c: Vec<f64>) -> f64 {
        if c.len() != self.r.len() {
            return f64::NEG_INFINITY;
        }
        let (m, sd) = crate::design::mean_sd(&c);
        if sd.is_nan() || sd <= 1e-12 || !sd.is_finite() {
            return f64::NEG_INFINITY;
        }
        let c = DVector::from_iterator(c.len(), c.iter().map(|v| (v - m) / sd));
        let u = self.p.phi.tr_mul(&c);
        let s = self.beta * c.dot(&c) - self.beta * self.beta * (u.transpose() * &self.cov * &u)[0];
        let q = self.beta * c.dot(&self.r);
        if s.is_nan() || s <= 1e-12 || !q.is_finite() {
            return f64::NEG_INFINITY;
        }
        let q2 = q * q;
        if q2 <= s {
            return 0.0;
        }
        0.5 * ((q2 - s) / s + (s / q2).ln())
    }
}

/// A shape searched: its parameters (positions in [0, 1] across each range) and its gain.
#[derive(Clone, Debug)]
struct Found {
    shape: Shape,
    u: Vec<f64>,
    gain: f64,
}

impl Found {
    fn expr(&self) -> Expr {
        self.shape.build(&self.u)
    }
}

/// The coarse grid's positions per parameter for a shape with `k` parameters.
fn per_param(k: usize) -> usize {
    match k {
        0 => 1,
        1 => 24,
        2 => 16,
        _ => 8,
    }
}

/// Every point of the coarse grid.
fn grid(k: usize) -> Vec<Vec<f64>> {
    let per = per_param(k);
    let mut out = vec![Vec::new()];
    for _ in 0..k {
        out = out
            .into_iter()
            .flat_map(|v| {
                (0..per).map(move |i| {
                    let mut w = v.clone();
                    w.push((i as f64 + 0.5) / per as f64);
                    w
                })
            })
            .collect();
    }
    out
}

/// Starts of the refinement on the coarse screen: the best points of a shape's grid (a relay's
/// evidence is sharply peaked in its switching points, and the grid's best may sit on a ridge
/// away from the peak).
const STARTS: usize = 4;

/// `shape` searched on the coarse screen: its grid, then the [`STARTS`] best points refined.
fn coarse(screen: &Screen<'_>, shape: &Shape) -> Option<Found> {
    // A depth-two shape's grid spans its inner parameters too, beside the starts at the inner
    // estimate: a relay in front of a lag switches at other points than the relay alone.
    let joint = if shape.inner.as_ref().is_some_and(|f| f.shape.params() >= 2)
        && shape.params() <= JOINT_PARAMS
    {
        grid(shape.params())
    } else {
        Vec::new()
    };
    let mut pts: Vec<Found> = inner_starts(shape)
        .iter()
        .flat_map(|start| {
            grid(shape.ranges.len())
                .into_iter()
                .map(move |g| start.iter().copied().chain(g).collect::<Vec<f64>>())
        })
        .chain(joint)
        .map(|u| {
            let gain = screen.gain_coarse(&shape.build(&u));
            Found {
                shape: shape.clone(),
                u,
                gain,
            }
        })
        .filter(|f| f.gain.is_finite())
        .collect();
    pts.sort_by(|a, b| b.gain.total_cmp(&a.gain));
    pts.truncate(if shape.params() == 0 { 1 } else { STARTS });
    // At depth one only: scanned too, a depth-two shape's places (beside its inner shape's
    // parameters, held) find optima of the bins' mean rows that every row does not share
    // (measured: a relay on a lagged supply, 1.41× the floor with its places refined from the
    // grid, 5.07× with them scanned too: a lag of 170 s, not 210 s, whose relay failed the
    // held-out blocks).
    if let Some(top) = pts.first().filter(|_| shape.inner.is_none()) {
        let scanned = scan_places(screen, top.clone());
        if scanned.gain > top.gain {
            pts.push(scanned);
        }
    }
    pts.into_iter()
        .map(|f| refine(f, |e| screen.gain_coarse(e)))
        .max_by(|a, b| a.gain.total_cmp(&b.gain))
}

/// Positions of a line scan across a place's range ([`scan_places`]): a 64th of the operand's
/// spread between them.
pub const LINE: usize = 64;

/// `f` with each place (a switching point, a bound, a shift: [`Role::Location`]) of a depth-one
/// shape scanned across its whole range on [`LINE`] positions, the other held; two passes.
/// Why: the evidence is peaked in a place more narrowly than the grid's step — a relay's
/// falling point 2 °C off loses 30 of 78 nats where the grid's step is 6 °C — and is flat
/// between the operand's values, where golden-section search cannot tell which way to go
/// (measured: a mode hop at 30 and 10 °C had its best grid point at 29.5 and −4 °C, 51 nats,
/// and was named through a 94 s lag, 3.45× the floor).
fn scan_places(screen: &Screen<'_>, mut f: Found) -> Found {
    let places: Vec<usize> = (0..f.shape.params())
        .filter(|&j| {
            f.shape
                .range_at(j)
                .is_some_and(|r| r.role == Role::Location)
        })
        .collect();
    for _ in 0..2 {
        let mut moved = false;
        for &j in &places {
            let best = (0..LINE)
                .map(|i| {
                    let mut u = f.u.clone();
                    if let Some(x) = u.get_mut(j) {
                        *x = (i as f64 + 0.5) / LINE as f64;
                    }
                    let g = screen.gain_coarse(&f.shape.build(&u));
                    (u, g)
                })
                .filter(|(_, g)| g.is_finite())
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((u, g)) = best.filter(|(_, g)| *g > f.gain) {
                f.u = u;
                f.gain = g;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    f
}

/// Where a depth-two shape's grid holds its inner parameters: at the inner shape's estimate, and
/// each inner parameter moved a quarter of its range either way (the lag that best explains the
/// residual alone may be several times the lag in front of a relay); one empty start at depth one.
fn inner_starts(shape: &Shape) -> Vec<Vec<f64>> {
    let Some(f) = &shape.inner else {
        return vec![Vec::new()];
    };
    let mut out = vec![f.u.clone()];
    for j in 0..f.u.len() {
        for d in [-INNER_MOVE, INNER_MOVE] {
            let mut u = f.u.clone();
            if let Some(x) = u.get_mut(j) {
                let to = (*x + d).clamp(0.0, 1.0);
                if (to - *x).abs() < 0.5 * INNER_MOVE {
                    continue;
                }
                *x = to;
            }
            out.push(u);
        }
    }
    out
}

/// The most parameters a depth-two shape's joint grid spans (8 positions each: 512 points).
const JOINT_PARAMS: usize = 3;

/// How far [`inner_starts`] moves an inner parameter (a fraction of its range).
const INNER_MOVE: f64 = 0.25;

/// `f` refined on `objective`: golden-section sweeps, one parameter at a time (a depth-two
/// shape's inner parameters with the outer ones), within a grid step of where it is.
fn refine(mut f: Found, objective: impl Fn(&Expr) -> f64) -> Found {
    f.gain = objective(&f.expr());
    let steps = f.shape.steps();
    let sweeps = if f.shape.inner.is_some() {
        JOINT_SWEEPS
    } else {
        SWEEPS
    };
    for _ in 0..sweeps {
        let mut moved = false;
        for (j, &step) in steps.iter().enumerate() {
            let at = f.u.get(j).copied().unwrap_or(0.5);
            let mut trial = f.u.clone();
            let (u, g) = crate::param::golden(
                |x| {
                    if let Some(t) = trial.get_mut(j) {
                        *t = x;
                    }
                    objective(&f.shape.build(&trial))
                },
                (at - step).max(0.0),
                (at + step).min(1.0),
                REFINE_STEPS,
            );
            if g > f.gain {
                if let Some(t) = f.u.get_mut(j) {
                    *t = u;
                }
                f.gain = g;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    f
}

/// Columns closer than this are one hypothesis on the training run: the share of one's variance
/// the other leaves unexplained (`1 − R²`; 10⁻³ is a difference of about 3 % of the spread).
const SAME_COLUMN: f64 = 1e-3;

/// `found` (best first) with each set of shapes whose training columns are the same hypothesis
/// ([`SAME_COLUMN`]) reduced to its simplest — depth one before depth two, then fewer parameters
/// — in the place of the set's best. Why: the language writes one function of the data in many
/// ways (a product with a supply that wanders ±2 % is the other factor; the square of that supply
/// is a straight line in it; a clamp of a kink the run barely reaches is a clamp), and a name
/// should be the simplest that fits (measured: `rate(sq(supply_v), 550)`, `supply_v *
/// abs(supply_v − 28)` and `clamp(abs(supply_v − 27.2), 0.68, 1.12)` named for the truths
/// `rate(supply_v, 600)`, `abs(supply_v − 28)` and `clamp(supply_v, 27.9, 28.3)`).
fn simplest(p: &Prepared, found: Vec<Found>) -> Vec<Found> {
    let complexity = |f: &Found| (usize::from(f.shape.inner.is_some()), f.u.len());
    let cols: Vec<Vec<f64>> = found.par_iter().map(|f| values(p, &f.expr())).collect();
    let kinds: Vec<(Vec<String>, Vec<String>)> =
        found.iter().map(|f| dynamics(&f.expr())).collect();
    let mut kept: Vec<(usize, Found)> = Vec::new();
    for (i, f) in found.into_iter().enumerate() {
        match kept
            .iter_mut()
            .find(|(j, _)| kinds[i] == kinds[*j] && same_column(&cols[i], &cols[*j]))
        {
            Some(slot) if complexity(&f) < complexity(&slot.1) => *slot = (i, f),
            Some(_) => {}
            None => kept.push((i, f)),
        }
    }
    kept.into_iter().map(|(_, f)| f).collect()
}

/// Whether one of `e`'s calls does nothing on the training run: `e` with that call replaced by
/// its operand has the same column ([`same_column`]). A lag shorter than a bin is its operand
/// there (measured: `rate(lag(t_coil_c, 30), 30)` tied `rate(t_coil_c)` and made "cannot tell").
fn needless(p: &Prepared, e: &Expr) -> bool {
    fn without(e: &Expr, k: &mut usize) -> Option<Expr> {
        match e {
            Expr::Call(name, args) => {
                if *k == 0 {
                    return args.first().cloned();
                }
                *k -= 1;
                let mut out = Vec::with_capacity(args.len());
                let mut done = None;
                for a in args {
                    match (&done, without(a, k)) {
                        (None, Some(r)) => {
                            out.push(r);
                            done = Some(());
                        }
                        _ => out.push(a.clone()),
                    }
                }
                done.map(|_| Expr::Call(name.clone(), out))
            }
            Expr::Neg(a) => without(a, k).map(|r| Expr::Neg(Box::new(r))),
            Expr::Binary(op, a, b) => match without(a, k) {
                Some(r) => Some(Expr::Binary(*op, Box::new(r), b.clone())),
                None => without(b, k).map(|r| Expr::Binary(*op, a.clone(), Box::new(r))),
            },
            Expr::Name(_) | Expr::Num(..) | Expr::Text(_) => None,
        }
    }
    let col = values(p, e);
    (0..)
        .map_while(|i| without(e, &mut { i }))
        .any(|stripped| same_column(&col, &values(p, &stripped)))
}

/// What an expression's dynamics are: the stateful functions it calls and the inputs it reads,
/// each sorted. Two shapes with the same training column and the same dynamics differ only in a
/// memoryless reshaping of values the run never took; two with different dynamics (a relay on a
/// lagged temperature against a wider relay on the temperature) are two physical hypotheses that
/// a run with other ramp rates would separate, and both are handed on for the verdict to say so.
fn dynamics(e: &Expr) -> (Vec<String>, Vec<String>) {
    fn calls(e: &Expr, out: &mut Vec<String>) {
        match e {
            Expr::Call(name, args) => {
                if lang::FUNCTIONS
                    .iter()
                    .any(|f| f.name == name.as_str() && f.stateful)
                {
                    out.push(name.clone());
                }
                for a in args {
                    calls(a, out);
                }
            }
            Expr::Neg(a) => calls(a, out),
            Expr::Binary(_, a, b) => {
                calls(a, out);
                calls(b, out);
            }
            Expr::Name(_) | Expr::Num(..) | Expr::Text(_) => {}
        }
    }
    let mut ops = Vec::new();
    calls(e, &mut ops);
    ops.sort();
    let mut names = names_in(e);
    names.sort();
    names.dedup();
    (ops, names)
}

/// Whether two training columns are one hypothesis ([`SAME_COLUMN`]); never when either is
/// missing or constant.
fn same_column(a: &[f64], b: &[f64]) -> bool {
    let varies = |v: &[f64]| crate::design::mean_sd(v).1 > 0.0;
    a.len() == b.len()
        && a.len() > 2
        && varies(a)
        && varies(b)
        && unexplained(a, &[&b.to_vec()]) < SAME_COLUMN
}

/// Whether `e`'s training column lies in the span of the base model's design (its linear terms
/// and Gaussians; [`SAME_COLUMN`]).
fn in_model(p: &Prepared, e: &Expr) -> bool {
    let v = values(p, e);
    if v.len() != p.phi.nrows() || v.len() < 3 {
        return false;
    }
    let cols: Vec<Vec<f64>> = p
        .phi
        .column_iter()
        .map(|c| c.iter().copied().collect())
        .collect();
    let refs: Vec<&Vec<f64>> = cols.iter().collect();
    unexplained(&v, &refs) < SAME_COLUMN
}

/// The binned training values of `e` (empty when they cannot be computed).
fn values(p: &Prepared, e: &Expr) -> Vec<f64> {
    p.binned(&[e.to_string()])
        .ok()
        .and_then(|c| c.into_iter().next())
        .unwrap_or_default()
}

/// The 5th and 95th percentiles of `v`.
fn spread(v: &[f64]) -> Option<(f64, f64)> {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.len() < 4 {
        return None;
    }
    s.sort_by(f64::total_cmp);
    let q = |f: f64| s.get(((s.len() - 1) as f64 * f).round() as usize).copied();
    Some((q(0.05)?, q(0.95)?))
}

/// The shapes of `f` over `operand` (a level or not): the ranges of its parameters from the
/// operand's values, a shift in front when `f` depends on where zero is.
fn shape_of(
    p: &Prepared,
    times: (f64, f64),
    f: &'static Function,
    b: Behaviour,
    operand: &Expr,
    level: bool,
) -> Option<Shape> {
    let own_location = f
        .params
        .iter()
        .any(|q| matches!(q.domain, Domain::Finite | Domain::NotBelowPrevious));
    // Where zero is matters for a square unless the model's own terms hold the operand: the
    // shift's linear part is then theirs (measured: `sq(supply_v − 28)` was named as
    // `sq(abs(supply_v − 28))`, and `lag(sq(supply_v − 28), 600)` as a lagged kink, 4.50× the
    // floor, with `supply_v` in no term of the model).
    let shift_matters = b.shift_matters || (b.shift_matters_alone && !in_model(p, operand));
    let shifted = level && shift_matters && !own_location;
    let (lo, hi) = spread(&values(p, operand))?;
    let width = hi - lo;
    if width.is_nan() || width <= 0.0 {
        return None;
    }
    let mut ranges = Vec::new();
    if shifted {
        ranges.push(Range {
            lo,
            hi,
            role: Role::Location,
        });
    }
    for q in f.params {
        ranges.push(param_range(q, times, Some((lo, hi))));
    }
    let switching = shifted && ranges.get(1).is_some_and(|r| r.role == Role::Threshold);
    if let Some(r) = ranges.get_mut(1).filter(|_| switching) {
        *r = Range {
            lo,
            hi,
            role: Role::Location,
        };
    }
    Some(Shape {
        operand: Some(operand.clone()),
        inner: None,
        op: Op::Call(f),
        shifted,
        switching,
        ranges,
        level,
    })
}

/// The range of parameter `q`: a time between half a bin and a third of the run, a threshold
/// between 1 % and 50 % of the operand's spread, a location across it.
fn param_range(q: &lang::Param, times: (f64, f64), operand: Option<(f64, f64)>) -> Range {
    if q.name.ends_with("_s") {
        return Range {
            lo: times.0,
            hi: times.1,
            role: Role::Time,
        };
    }
    let (lo, hi) = operand.unwrap_or((0.0, 1.0));
    let width = (hi - lo).max(1e-9);
    match q.domain {
        Domain::Finite | Domain::NotBelowPrevious => Range {
            lo,
            hi,
            role: Role::Location,
        },
        Domain::NonNegative | Domain::Positive => Range {
            lo: 0.01 * width,
            hi: 0.5 * width,
            role: Role::Threshold,
        },
    }
}

/// The signature of an expression: its text with every number replaced by `#` and every numeric
/// argument of a call dropped (the same shape at any parameter, a defaulted one included:
/// `rate(x)` and `rate(x, 67)` are one shape), and an outer chain of linear filters in one order
/// (they commute: `lag(rate(x))` is `rate(lag(x))`).
pub fn signature(e: &str) -> String {
    let s = numbered(e).replace(",#", "");
    let linear: Vec<&str> = behaviours()
        .iter()
        .filter(|(_, b)| b.linear)
        .map(|(f, _)| f.name)
        .collect();
    let mut chain: Vec<&str> = Vec::new();
    let mut rest = s.as_str();
    while let Some(name) = linear.iter().copied().find(|n| {
        rest.strip_prefix(n)
            .and_then(|r| r.strip_prefix('('))
            .and_then(|r| r.strip_suffix(')'))
            .is_some_and(balanced)
    }) {
        chain.push(name);
        rest = &rest[name.len() + 1..rest.len() - 1];
    }
    chain.sort_unstable();
    let mut out = rest.to_string();
    for name in chain.iter().rev() {
        out = format!("{name}({out})");
    }
    out
}

/// Whether every bracket in `s` closes, none before it opens.
fn balanced(s: &str) -> bool {
    let mut depth = 0i32;
    for ch in s.chars() {
        match ch {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ => {}
        }
        if depth < 0 {
            return false;
        }
    }
    depth == 0
}

/// `e` without spaces, every number `#`.
fn numbered(e: &str) -> String {
    let mut out = String::new();
    let mut prev_word = false;
    let mut in_num = false;
    for ch in e.chars().filter(|c| !c.is_whitespace()) {
        let starts_num = ch.is_ascii_digit() && !prev_word;
        if in_num && (ch.is_ascii_digit() || ch == '.' || ch == 'e' || ch == 'E') {
            continue;
        }
        in_num = false;
        if starts_num {
            in_num = true;
            out.push('#');
            prev_word = false;
            continue;
        }
        prev_word = ch.is_alphanumeric() || ch == '_';
        out.push(ch);
    }
    out
}

/// The atoms of `src`.
fn atoms(src: &Sources) -> Vec<Atom> {
    let mut out: Vec<Atom> = src
        .temperatures
        .iter()
        .map(|t| Atom {
            expr: Expr::name(t),
            level: true,
        })
        .collect();
    let th = &src.thermometers;
    for (i, a) in th.iter().enumerate() {
        for b in th.iter().skip(i + 1) {
            // A gradient is shifted too: a contact or a mode that switches at a thermal
            // difference of a kelvin is no less physical than one at zero. (Searched about zero
            // only, `hyst(t_anode_c − t_shell_c − 1, 0.5)` was named as a narrow clamp of the
            // gradient times the supply, 2.89× the floor; searched about any value it is named
            // exactly, 1.02×. It took `tcomp diagnose` on the RLG preset over its 2 s budget until
            // the coarse screen remembered the expressions it had scored: now the same time as
            // before, 3.0–3.5 s on the slower machine where it was 3.0–3.6 s.)
            out.push(Atom {
                expr: Expr::name(a) - Expr::name(b),
                level: true,
            });
        }
    }
    out.extend(src.inputs.iter().map(|c| Atom {
        expr: Expr::name(c),
        level: true,
    }));
    out
}

/// The composed candidate families for `src`, leaving out shapes `listed` (every other family)
/// already covers: those a member of one is, alone. A member of several expressions (a bank's
/// reading, `x` beside two lags of it) covers none of them one by one: it is another hypothesis
/// (measured: with its pieces counted as covered, `lag(heater_v, 900)` was never proposed behind
/// the reading `heater_v`, `lag(heater_v, 380)`, `lag(heater_v, 3400)`, whose refit made the
/// held-out blocks 43 % worse, and the run ended at 5.41× the floor where the truth reaches 1.15×).
pub fn propose(p: &Prepared, src: &Sources, listed: &[Family]) -> Vec<Family> {
    let Some(screen) = Screen::new(p) else {
        return Vec::new();
    };
    let covered: HashSet<String> = listed
        .iter()
        .flat_map(|f| &f.members)
        .filter_map(|m| match m.expressions.as_slice() {
            [e] => Some(signature(e)),
            _ => None,
        })
        .collect();
    let bin = p.figures.bin_s;
    let times = (0.5 * bin, (p.duration_s() / 3.0).max(bin));
    let functions = behaviours();
    let atoms = atoms(src);
    // A memoryless function of temperatures alone is a shape of the bias–temperature curve,
    // which the model's own terms in temperature fit (a kink, a saturation, a square): not a
    // missing effect. A stateful one (a relay, a lag, a rate) is a signal the model lacks.
    let thermal = |e: &Expr| names_in(e).iter().all(|n| src.temperatures.contains(n));
    let allowed = |f: &Function, operand: &Expr| f.stateful || !thermal(operand);

    // Depth one: every function over every atom, the products of two atoms, and the functions of
    // time alone.
    let mut shapes: Vec<Shape> = Vec::new();
    for a in &atoms {
        for &(f, b) in functions.iter().filter(|(f, _)| allowed(f, &a.expr)) {
            shapes.extend(shape_of(p, times, f, b, &a.expr, a.level));
        }
    }
    for (i, a) in atoms.iter().enumerate() {
        for b in atoms.iter().skip(i + 1) {
            shapes.push(Shape {
                operand: Some(b.expr.clone()),
                inner: None,
                op: Op::Times(a.expr.clone()),
                shifted: false,
                switching: false,
                ranges: Vec::new(),
                level: false,
            });
        }
    }
    for f in lang::FUNCTIONS
        .iter()
        .filter(|f| f.operands == Operands::None)
    {
        shapes.push(Shape {
            operand: None,
            inner: None,
            op: Op::Call(f),
            shifted: false,
            switching: false,
            ranges: f
                .params
                .iter()
                .map(|q| param_range(q, times, None))
                .collect(),
            level: false,
        });
    }
    let mut among = shapes.len();
    let inputs: HashSet<String> = src.inputs.iter().cloned().collect();
    // A rate is told by its measured behaviour: a linear filter whose output is no level.
    let is_rate = |s: &Shape| {
        matches!(&s.op, Op::Call(g) if functions
            .iter()
            .any(|(h, b)| h.name == g.name && b.linear && !b.keeps_level))
    };
    let rates: Vec<Shape> = shapes.iter().filter(|s| is_rate(s)).cloned().collect();
    let first = best(&screen, shapes, BEAM, (PER_OPERAND, &inputs));

    // Depth two: every function over the best, and their products with every atom.
    let mut next: Vec<Shape> = Vec::new();
    for n in &first {
        let e = n.expr();
        let level = n.shape.level
            && match &n.shape.op {
                Op::Call(f) => functions
                    .iter()
                    .any(|(g, b)| g.name == f.name && b.keeps_level),
                Op::Times(_) => false,
            };
        // A temperature's rate is not a temperature: a memoryless function of it (`abs(rate(T))`,
        // a bias the same on heating and cooling) is no shape of the bias–temperature curve.
        let of_a_rate = is_rate(&n.shape);
        for &(f, b) in functions
            .iter()
            .filter(|(f, _)| allowed(f, &e) || of_a_rate)
        {
            if matches!(&n.shape.op, Op::Call(g) if g.name == f.name && !b.keeps_level) {
                continue;
            }
            next.extend(shape_of(p, times, f, b, &e, level).map(|s| Shape {
                inner: Some(Box::new(n.clone())),
                ..s
            }));
        }
        for a in &atoms {
            next.push(Shape {
                operand: Some(e.clone()),
                inner: Some(Box::new(n.clone())),
                op: Op::Times(a.expr.clone()),
                shifted: false,
                switching: false,
                ranges: Vec::new(),
                level: false,
            });
        }
    }
    // An even function of a rate (its square, its size) has no linear part in the rate: the
    // rate's own gain says nothing of it, so every rate the beam left out is composed with the
    // even functions, its window searched with theirs (measured: `sq(rate(t_anode_c −
    // t_shell_c))` was never composed, `rate(t_anode_c − t_shell_c)` 36th of the depth-one
    // shapes behind products of temperatures and gradients). Evenness is measured, like every
    // behaviour: a function added to the language that forgets its operand's sign joins them.
    let composed: HashSet<String> = first
        .iter()
        .map(|f| signature(&f.expr().to_string()))
        .collect();
    let left_out: Vec<Found> = rates
        .par_iter()
        .filter_map(|s| coarse(&screen, s))
        .filter(|f| !composed.contains(&signature(&f.expr().to_string())))
        .collect();
    for n in &left_out {
        let e = n.expr();
        for &(f, b) in functions.iter().filter(|(f, b)| b.even && !f.stateful) {
            next.extend(shape_of(p, times, f, b, &e, false).map(|s| Shape {
                inner: Some(Box::new(n.clone())),
                ..s
            }));
        }
    }
    let floor = first
        .iter()
        .map(|f| f.gain)
        .fold(f64::NEG_INFINITY, f64::max);
    among += next.len();
    let mut second = best(&screen, next, BEAM, (0, &HashSet::new()));
    // A composition earns its second operator by explaining more than the best single one; or,
    // explaining as much as it (within what the run cannot tell), by explaining more than its own
    // inner shape: then it is another explanation of the same residual, and the refits decide.
    second.retain(|f| {
        f.gain > floor + EARN_NATS
            || (f.gain > floor - crate::score::INDISTINCT_NATS
                && f.shape
                    .inner
                    .as_ref()
                    .is_some_and(|i| f.gain > i.gain + EARN_NATS)
                && !needless(p, &f.expr()))
    });

    let mut all: Vec<Found> = first.into_iter().chain(second).collect();
    all.retain(|f| f.gain > 0.0 && !covered.contains(&signature(&f.expr().to_string())));
    all.sort_by(|a, b| b.gain.total_cmp(&a.gain));
    let mut seen = HashSet::new();
    all.retain(|f| seen.insert(signature(&f.expr().to_string())));
    all.truncate(PLAINEST * PROPOSED);
    let all: Vec<Found> = all
        .into_par_iter()
        .map(|f| plainest(f, |e| screen.gain(e)))
        .collect();
    let mut all = simplest(p, all);
    all.truncate(PROPOSED);
    all.iter().map(|f| family(f, src, among)).collect()
}

/// How many times [`PROPOSED`] of the leading shapes have their places written plainly before the
/// simplest of each column is chosen ([`plainest`]).
const PLAINEST: usize = 2;

/// Nats a place may cost to be written more plainly: half of what the run cannot tell apart
/// ([`crate::score::INDISTINCT_NATS`]), so that a relay's two switching points together stay
/// within it.
const PLAIN_SLACK: f64 = 0.5 * crate::score::INDISTINCT_NATS;

/// `f` with each place (a switching point, a shift, a bound) written with the fewest digits among
/// the values whose gain is within [`PLAIN_SLACK`] of the estimate's, the nearest such to it.
///
/// Why: a place is known only as well as the run pins it. Where the operand visits a few levels
/// (a heater stepping between set points), every switching point between two of them gives the
/// same training column, and the search stops anywhere on that plateau; where it passes the
/// point on a ramp, a tenth of a degree either way is within the noise. Printing the estimate to
/// a fixed grid then reports digits the run does not hold (measured: a relay on a heater named
/// `hyst(heater_v − 12.1895, 0.2395)` where `hyst(heater_v − 12.1, 0.15)` has the same training
/// column; on the verification run, which visits the levels between, 5.24× the floor against
/// 1.07×). The shortest number the run cannot tell from the estimate is the estimate stated to
/// the run's own precision: the parameter's share of a description length (Rissanen's two-part
/// code), as [`crate::description`] prices the structure.
fn plainest(mut f: Found, objective: impl Fn(&Expr) -> f64) -> Found {
    f.gain = objective(&f.expr());
    for j in 0..f.u.len() {
        let Some(r) = f.shape.range_at(j).filter(|r| r.role == Role::Location) else {
            continue;
        };
        let span = r.hi - r.lo;
        let Some(&u0) = f.u.get(j) else {
            continue;
        };
        if !(span.is_finite() && span > 0.0) {
            continue;
        }
        let v0 = r.at(u0);
        let quantum = 10f64.powi(-(r.decimals() as i32));
        let gain_at = |v: f64| {
            let mut u = f.u.clone();
            if let Some(x) = u.get_mut(j) {
                *x = ((v - r.lo) / span).clamp(0.0, 1.0);
            }
            objective(&f.shape.build(&u))
        };
        let tied = |v: f64| gain_at(v) >= f.gain - PLAIN_SLACK;
        // Each side: steps doubling from one quantum while the gain stays tied, then the edge
        // bisected between the last tied value and the first that is not.
        let edge = |dir: f64| {
            let (mut inside, mut step) = (v0, quantum);
            let mut outside = None;
            for _ in 0..PLAIN_STEPS {
                let v = v0 + dir * step;
                if !(r.lo..=r.hi).contains(&v) {
                    break;
                }
                if tied(v) {
                    inside = v;
                    step *= 2.0;
                } else {
                    outside = Some(v);
                    break;
                }
            }
            if let Some(mut out) = outside {
                for _ in 0..PLAIN_BISECTIONS {
                    let mid = 0.5 * (inside + out);
                    if tied(mid) {
                        inside = mid;
                    } else {
                        out = mid;
                    }
                }
            }
            inside
        };
        let (lo, hi) = (edge(-1.0), edge(1.0));
        let Some(v) = shortest_between(lo, hi, v0, quantum) else {
            continue;
        };
        // A relay's two switching points written as one would make it a comparator, which
        // chatters on the operand's noise: another function, not a plainer number.
        let other = f.shape.partner(j).and_then(|k| {
            let r = f.shape.range_at(k)?;
            f.u.get(k).map(|&u| r.rounded(r.at(u)))
        });
        if other.is_some_and(|o| (o - v).abs() < 0.5 * quantum) {
            continue;
        }
        if let Some(x) = f.u.get_mut(j) {
            *x = ((v - r.lo) / span).clamp(0.0, 1.0);
        }
        f.gain = objective(&f.expr());
    }
    f
}

/// Doubling steps of [`plainest`]'s search for the edge of the tied values, each way.
const PLAIN_STEPS: usize = 8;
/// Bisections of that edge.
const PLAIN_BISECTIONS: usize = 3;

/// The number in `[lo, hi]` with the fewest decimals (a multiple of the largest power of ten
/// that has one there, down to `quantum`), the nearest such to `at`.
fn shortest_between(lo: f64, hi: f64, at: f64, quantum: f64) -> Option<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi >= lo && quantum > 0.0) {
        return None;
    }
    let mut p = 10f64.powf(hi.abs().max(lo.abs()).max(quantum).log10().ceil());
    while p >= quantum * 0.999 {
        let first = (lo / p).ceil();
        let last = (hi / p).floor();
        if first <= last {
            let k = (at / p).round().clamp(first, last);
            let decimals = (-p.log10().round()).max(0.0) as usize;
            return Some(to_decimals(k * p, decimals));
        }
        p /= 10.0;
    }
    None
}

/// The first `keep` of `found` (sorted best first), and beside them each operand's first
/// `allowance` of the rest.
fn cut(
    found: Vec<Found>,
    keep: usize,
    allowance: &dyn Fn(&Found) -> usize,
    operand: &dyn Fn(&Found) -> Option<String>,
) -> Vec<Found> {
    let mut per: std::collections::HashMap<Option<String>, usize> = Default::default();
    let mut out = Vec::new();
    for (i, f) in found.into_iter().enumerate() {
        let n = per.entry(operand(&f)).or_default();
        *n += 1;
        if i < keep || *n <= allowance(&f) {
            out.push(f);
        }
    }
    out
}

/// The `keep` best of `shapes`, and beside them the `per_operand` best over each operand of
/// `diverse`: each on its coarse grid, the best refined.
fn best(
    screen: &Screen<'_>,
    shapes: Vec<Shape>,
    keep: usize,
    (per_operand, diverse): (usize, &HashSet<String>),
) -> Vec<Found> {
    let mut found: Vec<Found> = shapes
        .par_iter()
        .filter_map(|s| coarse(screen, s))
        .collect();
    found.sort_by(|a, b| b.gain.total_cmp(&a.gain));
    // The bins' mean rows smooth a noisy input before a relay or a clamp sees it: the coarse
    // screen's leaders are re-scored on every row before the beam is cut.
    let operand = |f: &Found| f.shape.operand.as_ref().map(Expr::to_string);
    let allowance = |f: &Found| {
        operand(f)
            .filter(|o| diverse.contains(o))
            .map_or(0, |_| per_operand)
    };
    let mut kept = cut(found, RESCORED * keep, &allowance, &operand);
    kept.par_iter_mut()
        .for_each(|f| f.gain = screen.gain(&f.expr()));
    kept.sort_by(|a, b| b.gain.total_cmp(&a.gain));
    cut(kept, keep, &allowance, &operand)
        .into_par_iter()
        .map(|f| refine(f, |e| screen.gain(e)))
        .collect()
}

/// The family of a composed candidate: the estimate, and the shape's members through it along
/// each parameter (what its evidence is marginalised over and each placebo searches).
fn family(f: &Found, src: &Sources, among: usize) -> Family {
    let e = f.expr();
    let mut exprs = vec![e.clone()];
    for (j, step) in f.shape.steps().into_iter().enumerate() {
        let per = (1.0 / step).round() as usize;
        for i in 0..per {
            let mut u = f.u.clone();
            if let Some(x) = u.get_mut(j) {
                *x = (i as f64 + 0.5) / per as f64;
            }
            let m = f.shape.build(&u);
            if !exprs.contains(&m) {
                exprs.push(m);
            }
        }
    }
    let member = |x: &Expr| Candidate {
        kind: kind_of(x, src),
        effect: describe_top(x, src),
        expressions: vec![x.to_string()],
        parameter: first_parameter(x),
        replaces: Vec::new(),
        refines: None,
    };
    Family {
        members: exprs.iter().map(member).collect(),
        search: None,
        searched: Searched::Alternatives {
            members: exprs.iter().map(Expr::to_string).collect(),
            among,
        },
    }
}

/// The first numeric parameter of the outermost call (for the report).
fn first_parameter(e: &Expr) -> Option<f64> {
    match e {
        Expr::Call(_, args) => args.iter().find_map(|a| match a {
            Expr::Num(v, _) => Some(*v),
            _ => None,
        }),
        _ => None,
    }
}

/// The kind of effect a composition stands for, by its outermost operator.
fn kind_of(e: &Expr, src: &Sources) -> EffectKind {
    let thermal = |x: &Expr| names_in(x).iter().all(|n| src.temperatures.contains(n));
    match e {
        Expr::Call(f, args) => match (f.as_str(), args.first()) {
            ("lag", Some(x)) if thermal(x) => EffectKind::LaggedElement,
            ("lag", _) => EffectKind::NonThermal,
            ("rate", Some(x)) if thermal(x) => EffectKind::Rate,
            ("hyst", _) => EffectKind::Hysteresis,
            ("warmup", _) => EffectKind::Warmup,
            (_, Some(x)) if thermal(x) => EffectKind::Poly,
            _ => EffectKind::NonThermal,
        },
        Expr::Binary(BinOp::Mul, a, b) if thermal(a) && thermal(b) => EffectKind::Shupe,
        _ => EffectKind::NonThermal,
    }
}

/// The column names an expression reads.
fn names_in(e: &Expr) -> Vec<String> {
    match e {
        Expr::Name(n) => vec![n.clone()],
        Expr::Neg(a) => names_in(a),
        Expr::Binary(_, a, b) => names_in(a).into_iter().chain(names_in(b)).collect(),
        Expr::Call(_, args) => args.iter().flat_map(names_in).collect(),
        Expr::Num(..) | Expr::Text(_) => Vec::new(),
    }
}

/// A number as printed.
fn n(v: f64) -> String {
    Expr::num(v).to_string()
}

/// "τ ≈ 25 min" or "τ ≈ 300 s".
fn minutes(tau: f64) -> String {
    if tau >= 600.0 {
        format!("τ ≈ {} min", n((tau / 60.0).round()))
    } else {
        format!("τ ≈ {} s", n(tau.round()))
    }
}

/// `x − c` or `x + c` as (`x`, `c`).
fn shifted_parts(e: &Expr) -> Option<(&Expr, f64)> {
    match e {
        Expr::Binary(BinOp::Sub, x, c) => match c.as_ref() {
            Expr::Num(c, _) => Some((x, *c)),
            _ => None,
        },
        Expr::Binary(BinOp::Add, x, c) => match c.as_ref() {
            Expr::Num(c, _) => Some((x, -*c)),
            _ => None,
        },
        _ => None,
    }
}

/// The engineer's name of a whole composed candidate.
fn describe_top(e: &Expr, src: &Sources) -> String {
    let temperature = |x: &Expr| matches!(x, Expr::Name(name) if src.temperatures.contains(name));
    match e {
        Expr::Call(f, args) => match (f.as_str(), args.as_slice()) {
            ("lag", [x, Expr::Num(t, _)]) if !temperature(x) => {
                format!("{} acts through a lag of {}", describe(x), minutes(*t))
            }
            ("hyst", [s, Expr::Num(h, _)]) => match shifted_parts(s) {
                Some((x, c)) if temperature(x) => format!(
                    "bias switches at {} on heating and {} on cooling ({})",
                    n(significant(c + h, 3)),
                    n(significant(c - h, 3)),
                    describe(x)
                ),
                _ => describe(e),
            },
            _ => describe(e),
        },
        _ => describe(e),
    }
}

/// The engineer's name of a composition, inside out.
fn describe(e: &Expr) -> String {
    match e {
        Expr::Name(name) => name.clone(),
        Expr::Num(v, _) => n(*v),
        Expr::Text(t) => t.clone(),
        Expr::Neg(a) => format!("−{}", describe(a)),
        Expr::Binary(BinOp::Sub, a, b) if matches!(b.as_ref(), Expr::Name(_)) => {
            format!("the gradient {}−{}", describe(a), describe(b))
        }
        Expr::Binary(BinOp::Mul, a, b) => format!("{} × {}", describe(a), describe(b)),
        Expr::Binary(op, a, b) => {
            let s = match op {
                BinOp::Add => "+",
                BinOp::Sub => "−",
                BinOp::Mul => "×",
                BinOp::Div => "/",
            };
            format!("{} {s} {}", describe(a), describe(b))
        }
        Expr::Call(f, args) => match (f.as_str(), args.as_slice()) {
            ("lag", [x, Expr::Num(t, _)]) => {
                format!("{} through a lag of {}", describe(x), minutes(*t))
            }
            ("rate", [x, ..]) => format!("the rate of {}", describe(x)),
            ("sq", [x]) => format!("the square of {}", describe(x)),
            ("abs", [s]) if shifted_parts(s).is_some() => match shifted_parts(s) {
                Some((x, c)) => format!("a kink in {} at {}", describe(x), n(c)),
                None => e.to_string(),
            },
            ("hyst", [s, Expr::Num(h, _)]) if shifted_parts(s).is_some() => {
                match shifted_parts(s) {
                    Some((x, c)) => format!(
                        "a relay on {} switching at {} rising and {} falling",
                        describe(x),
                        n(significant(c + h, 3)),
                        n(significant(c - h, 3))
                    ),
                    None => e.to_string(),
                }
            }
            ("hyst", [x, Expr::Num(h, _)]) => {
                format!("the rising/falling state of {} (±{})", describe(x), n(*h))
            }
            ("clamp", [x, lo, hi]) => format!(
                "{} saturating outside [{}, {}]",
                describe(x),
                describe(lo),
                describe(hi)
            ),
            _ => e.to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What each function does to a level is read off the evaluator: lag and rate need no shift,
    /// the square only beside its operand's linear term, a relay and a kink do; a lag keeps a
    /// level a level.
    #[test]
    #[allow(clippy::unwrap_used)]
    fn behaviours_are_measured_not_listed() {
        let b = |name: &str| lang::function(name).and_then(behaviour).unwrap();
        assert!(!b("lag").shift_matters && b("lag").keeps_level);
        assert!(!b("rate").shift_matters && !b("rate").keeps_level);
        assert!(!b("sq").shift_matters && b("sq").shift_matters_alone);
        assert!(!b("lag").shift_matters_alone && !b("rate").shift_matters_alone);
        assert!(b("hyst").shift_matters);
        assert!(b("abs").shift_matters);
        // Linear time-invariant: the filters, not the memoryless or switching functions.
        assert!(b("lag").linear && b("rate").linear);
        // Saturating or switching: the relay and the clamp, not the filters or the curves.
        for f in ["lag", "rate", "sq", "abs"] {
            assert!(!b(f).saturates, "{f}");
        }
        assert!(b("hyst").saturates && b("clamp").saturates);
        for f in ["sq", "abs", "hyst", "clamp"] {
            assert!(!b(f).linear, "{f}");
        }
        // Forgetting the operand's sign: the square and the size, nothing else.
        assert!(b("sq").even && b("abs").even);
        for f in ["lag", "rate", "hyst", "clamp"] {
            assert!(!b(f).even, "{f}");
        }
    }

    #[test]
    fn signatures_ignore_parameters_not_names() {
        assert_eq!(signature("lag(t_a1, 1800)"), signature("lag( t_a1 , 2e3)"));
        assert_ne!(signature("lag(t_a1, 1800)"), signature("lag(t_a2, 1800)"));
        assert_eq!(signature("hyst(T - 23.5, 4)"), "hyst(T-#)");
        assert_eq!(signature("rate(a - b)"), signature("rate(a - b, 67)"));
        // Linear filters commute; a relay does not commute with them.
        assert_eq!(
            signature("lag(rate(v, 64), 480)"),
            signature("rate(lag(v, 600))")
        );
        assert_ne!(
            signature("lag(hyst(v, 1), 60)"),
            signature("hyst(lag(v, 60), 1)")
        );
        assert_ne!(signature("lag(a) * rate(b)"), signature("rate(a) * lag(b)"));
    }

    #[test]
    fn a_relay_on_a_shifted_temperature_is_named_by_its_switching_points() {
        let src = Sources {
            temperatures: vec!["T".into()],
            ..Sources::default()
        };
        let e = Expr::call("hyst", [Expr::name("T") - Expr::num(30.0), Expr::num(5.0)]);
        assert_eq!(
            describe_top(&e, &src),
            "bias switches at 35 on heating and 25 on cooling (T)"
        );
        let l = Expr::call("lag", [Expr::name("supply_v"), Expr::num(240.0)]);
        assert_eq!(
            describe_top(&l, &src),
            "supply_v acts through a lag of τ ≈ 240 s"
        );
    }

    #[test]
    #[allow(clippy::unwrap_used)]
    fn a_relays_switching_points_are_written_exactly_whatever_their_size() {
        // A temperature spanning 90 °C: its places are printed to 0.1 °C, so switching points
        // 30.3 and 9.9 are written `hyst(T − 20.1, 10.2)`, not 20.1 ± 10 (two significant
        // figures of the half-width would put a wide relay's points on a 1 °C grid).
        let t = Range {
            lo: -30.0,
            hi: 60.0,
            role: Role::Location,
        };
        let relay = |at: Range| Shape {
            operand: Some(Expr::name("T")),
            inner: None,
            op: Op::Call(lang::function("hyst").unwrap()),
            shifted: true,
            switching: true,
            ranges: vec![at, at],
            level: true,
        };
        let u = |r: &Range, v: f64| (v - r.lo) / (r.hi - r.lo);
        let e = relay(t).build(&[u(&t, 30.3), u(&t, 9.9)]).to_string();
        assert_eq!(e, "hyst(T - 20.1, 10.2)");
        let e = relay(t).build(&[u(&t, 30.04), u(&t, 10.0)]).to_string();
        assert_eq!(e, "hyst(T - 20, 10)");
        // Its two points are a pair, which a plainer writing must not merge into a comparator.
        assert_eq!(relay(t).partner(0), Some(1));
        assert_eq!(relay(t).partner(1), Some(0));
        // A supply wandering 0.8 V: to 1 mV.
        let v = Range {
            lo: 27.7,
            hi: 28.5,
            role: Role::Location,
        };
        assert_eq!(v.rounded(28.21374), 28.214);
        assert_eq!(t.rounded(28.21374), 28.2);
    }

    #[test]
    fn a_place_is_written_with_the_fewest_digits_the_run_allows() {
        // A heater's relay anywhere between two visited levels: one decimal, the nearest.
        assert_eq!(shortest_between(12.2, 12.5, 12.43, 0.001), Some(12.4));
        // A switching point pinned to ±0.07 °C around 29.95: the whole degree.
        assert_eq!(shortest_between(29.93, 30.08, 29.95, 0.1), Some(30.0));
        assert_eq!(shortest_between(-0.3, 0.2, -0.1, 0.01), Some(0.0));
        // Pinned tighter than a decimal: the finest place.
        assert_eq!(shortest_between(9.951, 9.952, 9.9514, 0.001), Some(9.951));
        assert_eq!(shortest_between(1.0, 0.5, 0.7, 0.1), None);
    }

    #[test]
    fn grids_cover_every_parameter() {
        assert_eq!(grid(0).len(), 1);
        assert_eq!(grid(1).len(), 24);
        assert_eq!(grid(2).len(), 256);
        assert!(grid(2).iter().all(|u| u.len() == 2));
    }
}
