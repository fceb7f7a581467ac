//! Effects composed from the language's operators, hidden from a model given the rest of the
//! truth: a relay on a shifted temperature (a mode hop), the rate of a lagged input, an input
//! times a rate, a lagged rate, a saturating input, a kink in the bias-temperature curve, … — none
//! of them a listed family ([`tcomp_discover::compose`] composes them). Each is injected into a
//! simulated pair of runs by the core's own feature program; the diagnosis must name a
//! composition of the same shape (the same operators over the same inputs), its parameters
//! within tolerance of the truth's, and the refit with it must reach the verification run within
//! 1.2× the noise floor — or within 1.2× of what least squares on the exact truth form reaches,
//! when that stays above the floor. Every figure is printed beside its limit.
//!
//! `cargo test --release -p tcomp-discover --test composed -- --nocapture --test-threads 1`
//! (`DUMP=1` prints every candidate of each run, its Δ log evidence and expressions;
//! `ROUNDS=3` also runs the rounds a user runs and prints the final model's verification
//! residual; `SEED_OFFSET=1000` runs every scenario on fresh runs, for a held-out figure).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

mod support;
use support::*;

/// One scenario: the sensor's own effects (all given to the model), the seed, the composed effect
/// hidden from it, and its size in noise floors.
struct Scenario {
    name: &'static str,
    sensor: SensorKind,
    effects: &'static [EffectKind],
    seed: u64,
    hidden: &'static str,
    multiple: f64,
    /// With an idle auxiliary column beside the inputs.
    idle: bool,
}

/// The numbers of an expression, in order.
fn numbers(e: &str) -> Vec<f64> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut prev_word = false;
    for ch in e.chars().chain(std::iter::once(' ')) {
        if !cur.is_empty() && (ch.is_ascii_digit() || ch == '.' || ch == 'e') {
            cur.push(ch);
            continue;
        }
        if !cur.is_empty() {
            out.extend(cur.parse::<f64>().ok());
            cur.clear();
        }
        if ch.is_ascii_digit() && !prev_word {
            cur.push(ch);
        }
        prev_word = ch.is_alphanumeric() || ch == '_';
    }
    out
}

/// The shape of an expression: the composer's own signature (numbers and numeric arguments
/// dropped, so a defaulted window and a printed one are one shape).
fn shape(e: &str) -> String {
    tcomp_discover::compose::signature(e)
}

/// Runs `s`: returns the outcome's text, whether it named the shape, and the ratios after and
/// at the limit.
fn run_scenario(s: &Scenario) -> (bool, f64, f64, String) {
    let mut case = base_case(
        presets::with_effects(s.sensor, s.effects)
            .unwrap()
            .with_seed(s.seed + seed_offset()),
        &[],
    );
    if s.idle {
        case.sim.train = with_idle_input(&case.sim.train, 1);
        case.sim.verify = with_idle_input(&case.sim.verify, 2);
    }
    case.compose = true;
    let c = scaled(&case, s.hidden, s.multiple);
    let case = with_injected(case, &[(c, s.hidden.to_string())]);
    let o = run(&case);
    if std::env::var_os("DUMP").is_some() {
        for c in &o.diagnosis.candidates {
            println!(
                "DUMP {:+9.1} {}",
                c.delta_log_evidence,
                c.expressions.join(" ; ")
            );
        }
    }
    let named = o.diagnosis.verdict == Verdict::MissingEffect
        && o.top()
            .expressions
            .iter()
            .any(|e| shape(e) == shape(s.hidden));
    let features = if o.diagnosis.verdict == Verdict::MissingEffect {
        o.top().candidate().applied_to(&case.base)
    } else {
        case.base.clone()
    };
    let after = after_ratio(&case, &features);
    // The trainer's refit with the truth's own feature: what the fit reaches once it is named.
    let mut told = case.base.clone();
    told.push(s.hidden.to_string());
    let told = after_ratio(&case, &told);
    let limit = limit_ratio(&case);
    // `ROUNDS=n`: the rounds a user runs (`tcomp diagnose --rounds n`), each confirmed effect
    // added and the model refitted, and the final model's verification residual beside the limit.
    if let Some(n) = std::env::var("ROUNDS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        let fitted = fit(&case, &case.base);
        let bytes = fitted.model.to_bytes().unwrap();
        let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
        let r = tcomp_discover::diagnose_rounds(
            &model,
            &case.sim.train,
            Some(&case.sim.verify),
            &options(&case),
            n,
        )
        .unwrap();
        let last = after_ratio(&case, &r.final_features);
        println!(
            "ROUNDS {}: final {:?} {last:.2}× (limit {limit:.2}×; within 1.2× of it: {}); {}",
            s.name,
            r.final_features,
            last <= 1.2 * limit.max(1.0),
            r.stopped
        );
    }
    let text = format!(
        "{}: hidden `{}`\n{}  after {features:?}: {after:.2}× the floor (limit {limit:.2}×; \
         the trainer told the truth {told:.2}×)",
        s.name, s.hidden, o.text
    );
    println!("{text}");
    if named {
        let (truth, found) = (numbers(s.hidden), numbers(&o.top().expressions[0]));
        println!("  parameters {found:?} for {truth:?}");
    }
    (named, after, limit, text)
}

/// Runs `s` and asserts: the verdict names a composition of the hidden one's shape, each of its
/// parameters within `tol` of the truth's (a fraction of the truth's size, or to the operand's
/// size, at least 1), and the refit with it within 1.2× the floor or 1.2× the limit.
fn check(s: &Scenario, tol: f64) {
    let (named, after, limit, text) = run_scenario(s);
    assert!(named, "{text}");
    assert!(after <= 1.2 * limit.max(1.0), "{text}");
    // The trailing parameters compared (a default the truth leaves out may be printed).
    let found = numbers(&text_expression(&text));
    let truth = numbers(s.hidden);
    assert!(
        found.len() >= truth.len(),
        "{found:?} for {truth:?}\n{text}"
    );
    let found = &found[found.len() - truth.len()..];
    for (f, t) in found.iter().zip(&truth) {
        assert!(
            (f - t).abs() <= tol * t.abs().max(1.0),
            "{found:?} for {truth:?}\n{text}"
        );
    }
}

/// A composed shape whose regime the run barely visits is no candidate: here two clamps of a rate
/// to a band the rate crosses inside one block only (`clamp(rate(supply_v, 4000), 0.00666,
/// 0.00669)`) led the search, and the trainer found their columns constant — the refit failed and
/// passed its slot on. Now no candidate's refit fails, and the product of a relay on the supply
/// with T, which they pushed to third, is refitted (it fails on the held-out blocks, which the
/// scenario `a_relay_on_an_input_scaled_by_temperature` keeps as a miss).
#[test]
fn a_shape_the_run_barely_visits_takes_no_refit_slot() {
    let (_, _, _, text) = run_scenario(&Scenario {
        name: "relay on an input × temperature, refitted",
        sensor: SensorKind::Qma,
        effects: &[EffectKind::Poly],
        seed: 101,
        hidden: "t_qma_c * hyst(supply_v - 28, 0.3)",
        multiple: 6.0,
        idle: false,
    });
    let failed = text
        .lines()
        .filter(|l| l.contains("the refit with it failed"))
        .count();
    // Its row in the candidate table (the verdict may name it as the closest, too).
    let product = text
        .lines()
        .find(|l| l.starts_with("  ") && l.contains("× a relay on supply_v"))
        .unwrap_or_default();
    assert_eq!(failed, 0, "{text}");
    assert!(!product.is_empty(), "{text}");
    assert!(!product.contains("not among the"), "{text}");
    let refit = product
        .split(" refit ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|v| v.parse::<f64>().ok());
    assert!(refit.is_some_and(f64::is_finite), "{text}");
}

/// A bank's reading over an input (the heater directly and through lags of 380 s and 57 min) is
/// another hypothesis than one lag of the heater, not a cover for it: the composed search proposes
/// the single lag beside it. (Before, each expression of the reading counted as covered, and
/// `lag(heater_v, τ)` was never a candidate.)
#[test]
fn a_banks_reading_leaves_the_single_lag_proposed() {
    let (_, _, _, text) = run_scenario(&Scenario {
        name: "lagged second input, proposed",
        sensor: SensorKind::Qma,
        effects: &[EffectKind::Poly],
        seed: 95,
        hidden: "lag(heater_v, 900)",
        multiple: 6.0,
        idle: true,
    });
    let reading = text
        .lines()
        .any(|l| l.contains("heater_v acts directly and through lags"));
    let single = text
        .lines()
        .any(|l| l.contains("heater_v acts through a lag of τ"));
    assert!(reading && single, "{text}");
}

/// The expression the verdict says to add (`--feature '…'`).
fn text_expression(text: &str) -> String {
    text.split("--feature '")
        .nth(1)
        .and_then(|r| r.split('\'').next())
        .unwrap_or_default()
        .to_string()
}

macro_rules! scenarios {
    ($($(#[$attr:meta])* $test:ident: $name:literal, $sensor:ident, [$($eff:ident),*], $seed:literal, $hidden:literal, $mult:literal, $idle:literal, $tol:literal;)+) => {
        $(
            #[test]
            $(#[$attr])*
            fn $test() {
                check(&Scenario {
                    name: $name,
                    sensor: SensorKind::$sensor,
                    effects: &[$(EffectKind::$eff),*],
                    seed: $seed,
                    hidden: $hidden,
                    multiple: $mult,
                    idle: $idle,
                }, $tol);
            }
        )+
    };
}

scenarios! {
    a_mode_hop_on_heating_and_cooling: "mode hop", Qma, [Poly], 31, "hyst(t_qma_c - 20, 10)", 6.0, false, 0.02;
    a_relay_on_an_input: "relay on an input", Qma, [Poly], 35, "hyst(supply_v - 28.2, 0.2)", 6.0, true, 0.02;
    /// Named exactly while places were printed to three significant figures (0.1 V on a 28 V
    /// supply). Since they are written to the run's own precision: named `clamp(abs(supply_v −
    /// 27.36), 0.5, 0.952)`, bounds at 27.86 and 28.31 V, whose refit explains the training run
    /// 11 nats better than the truth's 27.9 and 28.3: 2.31× where the truth form reaches 1.06×.
    /// Since the compositions' refit slots go by the placebo leg's statistic (`confirm`): named
    /// exactly, `clamp(supply_v, 27.9, 28.3)`, 1.06×.
    a_saturating_input: "saturating input", Qma, [Poly], 36, "clamp(supply_v, 27.9, 28.3)", 6.0, true, 0.02;
    the_rate_of_an_input: "rate of an input", Qma, [Poly], 41, "rate(supply_v, 600)", 6.0, true, 0.25;
    a_relay_on_a_gradients_rate: "relay on a gradient's rate", Rlg, [Poly], 42, "hyst(rate(t_anode_c - t_shell_c), 0.05)", 6.0, false, 0.25;
    /// Not identifiable on this training run (verdict none, 2.03× the floor where the truth form
    /// reaches 1.01×): the QMA profile (20 → 50 → −30 °C) crosses the band once, cooling, so on it
    /// the relay is a step in T at −8 °C and its upper switching point is never exercised; the
    /// step's edge is all the model of T leaves (the truth gains 32 nats, the same relay 1 °C off
    /// under 4). The verification run heats through the band.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_narrow_mode_hop: "narrow mode hop", Qma, [Poly], 32, "hyst(t_qma_c + 5, 3)", 6.0, false, 0.02;
    /// Named as `lag(rate(supply_v, 64), 480)`, the same shape (linear filters commute): 1.25×
    /// where the truth form reaches 1.18× (was "cannot tell", 7.5×, before the inner lag was
    /// re-estimated with the outer rate).
    the_rate_of_a_lagged_input: "rate of a lagged input", Qma, [Poly], 33, "rate(lag(supply_v, 600))", 6.0, true, 0.25;
    /// Not identifiable here: the supply wanders ±2 %, so the product is 28× the rate of T within
    /// the noise. Verdict "cannot tell" between the rate of T and two thermal paths (τ 120 s and
    /// 22 min, the rate in another form), either at about 1.2× where the truth form reaches 1.14×
    /// (before: two thermal paths named, 1.20×; before still blocks stopped voting: none, 8.4×).
    #[ignore = "not identifiable here: run with --ignored to measure it"]
    an_input_times_a_rate: "input × rate", Qma, [Poly], 34, "supply_v * rate(t_qma_c)", 6.0, false, 0.25;
    /// Named as the nearest listed shape, `lag(t_qma_c, 1200)` (measured 1.73× where the truth
    /// form reaches 1.51×).
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_lagged_rate: "lagged rate", Qma, [Poly], 37, "lag(rate(t_qma_c), 1200)", 6.0, false, 0.25;
    /// Named `lag(clamp(supply_v, 27.9, 28.4), 580)`, 1.98× where the truth form reaches 1.01×,
    /// until a depth-two shape's grid spanned its inner parameters too: the relay alone is best
    /// at 28.4 ± 0.65, the relay in front of the lag at 28.2 ± 0.2. Now named exactly, 1.01×.
    a_lagged_relay_on_an_input: "lagged relay on an input", Qma, [Poly], 39, "lag(hyst(supply_v - 28.2, 0.2), 600)", 6.0, true, 0.25;
    /// Not identifiable on this run: the supply wanders ±2 %, so `supply_v * t_qma_c` is 28·T
    /// to within the noise, which the model's terms in T already fit (verdict none, 1.00× the
    /// floor; least squares on the truth form 1.19×).
    #[ignore = "not identifiable here: run with --ignored to measure it"]
    an_input_times_temperature: "input × temperature", Qma, [Poly], 40, "supply_v * t_qma_c", 6.0, false, 0.25;
    /// Named a relay on `t_qma_c` itself, switching at 34.6 and −23.4, 1.85× where the truth
    /// form reaches 0.91×, while a half-width was printed to two significant figures (29, not
    /// 28.95): with one ramp each way at one rate the lag in front of the relay and a wider band
    /// tied on that grid, then "cannot tell" (5.53×), then the wider relay by the structure prior
    /// (1.85×). With places written to the run's precision the lagged relay is pinned: named
    /// exactly, 0.91×, the wider relay 68 nats behind in its refit. Since each place is scanned
    /// across its whole range (`compose::LINE`), the search finds the wider relay's best
    /// points, 35 and −23.3: its refit ties the lagged relay's (+112.2 against +112.0 nats) and
    /// the structure prior names it, 1.85× (+10000: "cannot tell", 5.33×). A run with one ramp
    /// rate cannot tell a lag in front of a relay from a wider band; the verdict should say so.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_mode_hop_seen_through_a_lag: "mode hop of a lagging element", Qma, [Poly], 38, "hyst(lag(t_qma_c, 1800) - 15, 8)", 6.0, false, 0.25;
}

// Held out of the design: written after it was fixed and run once, each figure as measured
// (BENCHMARKS.md); a miss stays ignored with its figure rather than the design tuned to it.
scenarios! {
    a_saturating_lagged_input: "saturating lagged input", Qma, [Poly], 51, "clamp(lag(supply_v, 900), 27.8, 28.4)", 6.0, true, 0.25;
    /// Named as the gradient alone, 1.04× where the truth form reaches 1.03×: the supply wanders
    /// ±2 %, so the product is 28× the gradient within the noise (the run cannot tell them).
    #[ignore = "not identifiable here: run with --ignored to measure it"]
    a_gradient_times_an_input: "gradient × input", Rlg, [Poly], 52, "(t_anode_c - t_shell_c) * supply_v", 6.0, false, 0.25;
    a_v_shaped_input: "V-shaped input", Qma, [Poly], 53, "abs(supply_v - 28)", 6.0, true, 0.25;
    /// Not identifiable here: the unit is powered on at 20 °C and held there while it warms up,
    /// so on this run the product is 20× a warm-up. Named `warmup(850)`, 1.02× where the truth
    /// form reaches 1.00× (first run: verdict none, 5.67× — the held-out blocks could not test
    /// an effect that moves in one block only, and now cut that block into parts).
    #[ignore = "not identifiable here: run with --ignored to measure it"]
    a_warm_up_scaled_by_temperature: "warm-up × temperature", Qma, [Poly], 54, "warmup(900) * t_qma_c", 6.0, false, 0.25;
}

// A second held-out set (2026-11-28, fifth session): compositions written after the design was
// fixed, of kinds no earlier scenario has, run once; figures in BENCHMARKS.md.
scenarios! {
    /// First run: verdict none, 7.16× the floor — a memoryless function of temperatures alone
    /// was pruned as a shape of the bias–temperature curve, and a temperature's *rate* was taken
    /// for a temperature. With rates told apart (by their measured behaviour, not by name):
    /// `abs(rate(t_shell_c, 67))`, 1.03× where the truth form reaches 1.02×. Development since.
    the_size_of_a_temperature_rate: "size of a temperature rate", Rlg, [Poly], 61, "abs(rate(t_shell_c))", 6.0, false, 0.25;
    /// First run: named `rate(hyst(supply_v - 28.1, 0.05), 290)`, 2.60× where the truth form
    /// reaches 1.26×: the truth's own shape led by evidence (+573 nats) and beat its placebos, but
    /// the held-out blocks' refits chose their basis again without each block and judged that
    /// choice. With them pinned to the basis the whole run chose (development since): named
    /// `rate(clamp(supply_v, 27.9, 28.3), 290)`, 1.29×.
    the_rate_of_a_saturating_input: "rate of a saturating input", Qma, [Poly], 62, "rate(clamp(supply_v, 27.9, 28.3), 300)", 6.0, true, 0.25;
    /// Named as `sq(abs(supply_v - 28))` — the same function (`sq` of `abs` is `sq`), the centre
    /// exact — at 1.07× the floor where the truth form reaches 1.07×; the shape check here is
    /// written out, not algebraic, so it counts another shape. (`sq` takes no shift of its own:
    /// `sq(x − c)` is in the span of `sq(x)`, `x` and 1, which holds only when `x` is in the model.)
    #[ignore = "named as an equal function the shape check does not recognise: run with --ignored"]
    a_parabola_in_an_input: "parabola in an input", Qma, [Poly], 63, "sq(supply_v - 28)", 6.0, true, 0.25;
}

// A third held-out set (2026-11-29): compositions of kinds no earlier scenario has, written after
// the depth-two grid was made to span the inner parameters, and run once (1 of 5 named); figures
// in BENCHMARKS.md. The lagged V-shaped input set the per-input beam and the held-out refits'
// pinned basis, so it is development since.
scenarios! {
    /// Named exactly while places were printed to three significant figures, 1.40×. Since they
    /// are written to the run's precision: `hyst(lag(supply_v, 270) − 28.2, 0.17)`, whose refits
    /// without each held-out block predict it 322 % worse (a switching point 0.02 V away changes
    /// which blocks see the relay's upper state): "cannot tell", 5.68× with nothing added.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_relay_on_a_lagged_input: "relay on a lagged input", Qma, [Poly], 71, "hyst(lag(supply_v, 300) - 28.2, 0.15)", 6.0, true, 0.25;
    /// First run: verdict "cannot tell" (a clamp of an idle heater column's rate), 10.96× where
    /// the truth form reaches 1.14×: `abs(supply_v − 28.1)` was seventh at depth one and never
    /// composed. Development since: with each input's two best shapes composed, the lag of it led
    /// (+540 nats) but the refit without the cooling block chose Gaussians in T where the whole
    /// run chose the cubic, and predicted that block worse (20.8 → 38.0); with the blocks' refits
    /// pinned to the whole run's basis, named `lag(abs(supply_v − 28.1), 910)`, 1.12×.
    a_lagged_v_shaped_input: "lagged V-shaped input", Qma, [Poly], 72, "lag(abs(supply_v - 28.1), 900)", 6.0, true, 0.25;
    /// Named as the two gradients (a listed family), 1.00× where the truth form reaches 1.00×
    /// (1.60× before the additive fit had ramps, 1.16× before a term paid for its choice among
    /// the dictionary's): a memoryless function of thermometers alone is pruned as a curve
    /// shape, a gradient's too.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_saturating_gradient: "saturating gradient", Rlg, [Poly], 73, "clamp(t_anode_c - t_shell_c, 0.5, 4)", 6.0, false, 0.25;
    /// Verdict none, 3.95× where the truth form reaches 0.98×: `clamp` of a lagged temperature is
    /// pruned as a shape of the bias–temperature curve.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_saturating_lagging_element: "saturating lagging element", Qma, [Poly], 74, "clamp(lag(t_qma_c, 1200), -10, 30)", 6.0, false, 0.25;
    /// Verdict "cannot tell" (the rate of a wide relay on T), 3.46× where the truth form reaches
    /// 1.59× (the trainer told the truth 1.58×).
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_lagged_mode_hop: "lagged mode hop", Qma, [Poly], 75, "lag(hyst(t_qma_c - 10, 5), 600)", 6.0, false, 0.25;
}

// A fourth held-out set (2026-11-29): kinds no earlier scenario has, written after the held-out
// refits were pinned to the whole run's basis, and run once (in the workspace's test profile): 1
// of 5 named with its shape; figures in BENCHMARKS.md.
scenarios! {
    /// First run: named `lag(hyst(t_cathode_c - t_shell_c, 1.9), 420)` — the wrong gradient and
    /// shape — on the training blocks' −32 %, while on the verification run it changes nothing
    /// (−0.2 %): 8.67× where the truth form reaches 1.00× (the trainer told the truth: 1.00×).
    /// Since a rival that fails only the blocks' vote counts (`verdict::rival`): "cannot tell"
    /// between that and the rate of the relay (−40 % held out, 1.8 nats more), 8.57×; no invented
    /// effect, but the truth's shape is still not among the candidates. Since every rate the
    /// beam leaves out is composed with the even functions (`compose::propose`): named exactly,
    /// `sq(rate(t_anode_c - t_shell_c, 73))`, 1.01× where the truth form reaches 1.00×.
    the_square_of_a_gradients_rate: "square of a gradient's rate", Rlg, [Poly], 81, "sq(rate(t_anode_c - t_shell_c))", 6.0, false, 0.25;
    /// First run: "cannot tell" between `(t_anode_c - t_shell_c) * rate(T, 53)` (the truth's
    /// shape, with T for the shell) and the gradient's own family, their refits 0.9 nats apart:
    /// 6.97× with neither added, where the truth form reaches 1.04× (told: 1.07×).
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_gradient_times_a_rate: "gradient × rate", Rlg, [Poly], 82, "(t_anode_c - t_shell_c) * rate(t_shell_c)", 6.0, false, 0.25;
    /// First run: named `lag(hyst(supply_v - 28, 0), 1400)` — a step of the supply where the
    /// truth saturates over 0.5 V, through a longer lag — 1.08× where the truth form reaches
    /// 1.06× (1.12× since an additive term pays for its choice): the figure is met, the shape is
    /// not. Since each place is scanned across its whole range (`compose::LINE`): named
    /// `lag(clamp(supply_v, 27.9, 28.2), 1200)`, 1.18× (+7000: 1.70×, +8000: 4.34×, +10000:
    /// 2.08×, missed).
    a_lagged_saturating_input: "lagged saturating input", Qma, [Poly], 83, "lag(clamp(supply_v, 27.8, 28.3), 1200)", 6.0, true, 0.25;
    /// Not identifiable on this run: the heater steps between set levels, and every rising point
    /// between 12.14 and 12.40 V gives the same training column. Named exactly (1.07×) while a
    /// place was printed to three significant figures; written to the run's precision, the
    /// plainest number there is 12.3 (the truth 12.25): `hyst(heater_v − 12.125, 0.175)`, 2.48×
    /// on the verification run, which visits the levels between.
    #[ignore = "not identifiable here: run with --ignored to measure it"]
    a_relay_on_a_second_input: "relay on a second input", Qma, [Poly], 84, "hyst(heater_v - 12.1, 0.15)", 6.0, true, 0.25;
    /// First run: named `warmup(2000)`, one time constant for the two in series: 1.32× where the
    /// truth form reaches 0.97× (told: 0.97×).
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_lagged_warm_up: "lagged warm-up", Qma, [Poly], 85, "lag(warmup(600), 1200)", 6.0, false, 0.25;
}

#[test]
fn shapes_and_numbers_are_read() {
    assert_eq!(shape("hyst(t_qma_c - 35.5, 6)"), "hyst(t_qma_c-#)");
    assert_eq!(shape("rate(a - b, 30)"), shape("rate(a - b)"));
    assert_eq!(numbers("hyst(t_qma_c - 35.5, 6e1)"), vec![35.5, 60.0]);
}

// A fifth set (2026-11-29): kinds no earlier scenario has, written after a composition that ties
// the best single shape was handed on (and shapes of one column named by the simplest), and run
// once: 1 of 5 named with its shape, and one wrong effect. Changes were then made from its misses
// (a square shifted where its operand is no term of the model, a beam of 8, a rival failing only
// its placebos on other inputs), so it is no longer held out: 2 of 5 now; figures in
// BENCHMARKS.md.
scenarios! {
    the_size_of_an_inputs_rate: "size of an input's rate", Qma, [Poly], 91, "abs(rate(supply_v, 300))", 6.0, false, 0.25;
    /// First run: named `lag(abs(supply_v - 28), 590)`, a lagged kink, 4.50× where the truth form
    /// reaches 1.31×: the square was not shifted, as if the model's linear terms held `supply_v`.
    /// Then named `lag(sq(supply_v - 28), 590)`, 1.28×; since places are written to the run's
    /// precision, `lag(sq(supply_v − 28), 650)`, 1.60×.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_lagged_parabola_in_an_input: "lagged parabola in an input", Qma, [Poly], 92, "lag(sq(supply_v - 28), 600)", 6.0, false, 0.25;
    /// First run: named `clamp((t_anode_c - t_shell_c) * supply_v, 41, 42.9)` (a step of the
    /// gradient, through the supply that wanders ±2 %), 2.89× where the truth form reaches 1.01×:
    /// a relay on a gradient was searched about zero only. Searched about any value (once the
    /// coarse screen remembered its expressions, which paid for it): named exactly,
    /// `hyst(t_anode_c - t_shell_c - 0.996, 0.51)`, 1.02×.
    a_relay_on_a_gradient: "relay on a gradient", Rlg, [Poly], 93, "hyst(t_anode_c - t_shell_c - 1, 0.5)", 6.0, false, 0.25;
    /// First run and since: "cannot tell", a lag of the thermometer no better than its placebos;
    /// 6.34× with nothing added, where the truth form reaches 0.96×. The training run ramps at
    /// one rate (3 °C/min), so a rate that saturates below it is a relay on the rate's sign there.
    /// Its own shape led (+516 nats, far above its placebos) but the joint refits predicted the
    /// blocks 45.7 % worse. Since the second look in the additive structure
    /// (`confirm::additive`): named, `clamp(rate(t_qma_c, 67), -0.0301, 0.0215)`, 1.04×.
    a_saturating_temperature_rate: "saturating temperature rate", Qma, [Poly], 94, "clamp(rate(t_qma_c), -0.025, 0.025)", 6.0, false, 0.25;
    /// First run: named `lag(t_qma_c, 1200)` — a wrong effect — on the blocks' −19 %; on the
    /// verification run +301 %: 10.19× where the truth form reaches 1.38× (told: 1.15×). Since a
    /// rival on other inputs that fails only its placebos counts (`verdict::rival`): "cannot
    /// tell" between it and a kink in `heater_v` (199 nats and −83 % against 138 and −19 %),
    /// 5.41× with nothing added. A linear term in `heater_v` makes the held-out blocks worse
    /// (−130 %), as the heater's range differs block to block. The truth's shape was no candidate
    /// while the bank's reading (the heater directly and through two lags) counted as covering
    /// each of its lags; it is now proposed (`lag(heater_v, 700)`, 394 nats, see
    /// `a_banks_reading_leaves_the_single_lag_proposed`), but its joint refit makes the held-out
    /// blocks 183 % worse and it fails its placebos (−1.9 against +2.2): still 5.41×.
    /// With the refits offering the additive structure where the features read an input (tried,
    /// not kept: see `a_kink_in_a_second_input`): named as the heater acting directly and through
    /// lags of 380 s and 57 min (a listed family), 1.42× where the truth form reaches 1.38×.
    /// Since the second look in the additive structure (`confirm::additive`, banks of lags left
    /// out): the heater named as a linear term, `heater_v`, 2.34× — the right input, not yet its
    /// lag. Since the placebos' noise is re-read from each model's own residual (one
    /// Cochrane–Orcutt step, `placebo`): named, `lag(heater_v, 700)`, 1.28× (the base's residual
    /// read as drift, ρ 0.995, under which the lag had failed its placebos). It beat them by 0.1
    /// nats (2.3 against 2.2). Since the compositions' refit slots go by the placebo leg's
    /// statistic (`confirm`), `rate(heater_v, 7200)` takes the second slot where a kink of the
    /// heater held it, its placebos raise the threshold to 3.9, and the lag fails them: named
    /// `heater_v` again, 2.34×.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_lagged_second_input: "lagged second input", Qma, [Poly], 95, "lag(heater_v, 900)", 6.0, true, 0.25;
}

// A sixth held-out set (2026-11-29): kinds no earlier scenario has, written after the changes the
// fifth set led to, and run once: 2 of 5 pass (3 named with their shape); figures in
// BENCHMARKS.md.
scenarios! {
    /// First run: none; 6.48× where the truth form reaches 1.16×. The product was third by
    /// evidence, but two clamps of a rate whose refits could not be made held both of the
    /// compositions' refit slots. Since a failed refit passes its slot on, it is refitted and
    /// fails on the held-out blocks (2 of 4 improved, −5.4 % pooled): none, 6.48×.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_relay_on_an_input_scaled_by_temperature: "relay on an input × temperature", Qma, [Poly], 101, "t_qma_c * hyst(supply_v - 28, 0.3)", 6.0, false, 0.25;
    /// First run: named `sq(rate(t_qma_c, 100))`, the truth's shape with a 100 s window for its
    /// 60 s, 1.22× where the truth form reaches 0.92× (told: 0.97×): 2 % over the figure's bound.
    /// Since places are written to the run's precision: two lags and a Shupe term, 11.75× (a
    /// lagged relay on T and a lagged clamp of the supply took the square's refit slots). Since
    /// those slots go by the placebo leg's statistic (`confirm`): `sq(rate(t_qma_c, 100))` again,
    /// 1.22×.
    #[ignore = "a known miss: run with --ignored to measure it"]
    the_square_of_a_temperature_rate: "square of a temperature rate", Qma, [Poly], 102, "sq(rate(t_qma_c))", 6.0, false, 0.25;
    a_lagged_gradient_of_another_pair: "lagged gradient of another pair", Rlg, [Poly], 103, "lag(t_anode_c - t_cathode_c, 1200)", 6.0, false, 0.25;
    a_kink_in_a_lagged_input: "kink in a lagged input", Qma, [Poly], 104, "abs(lag(supply_v, 600) - 28.1)", 6.0, false, 0.25;
    /// First run: none, 1.04× with nothing added, where the truth form reaches 1.01× and the
    /// trainer told the truth 1.12×: on this run the relay is not worth its feature.
    #[ignore = "not identifiable here: run with --ignored to measure it"]
    a_mode_hop_on_another_thermometer: "mode hop on another thermometer", Rlg, [Poly], 105, "hyst(t_anode_c - 40, 3)", 6.0, false, 0.25;
}

// A seventh held-out set (2026-11-29, eighth session): kinds no earlier scenario has, written after
// a failed refit was made to pass its slot on, and run once: 2 of 5 pass; figures in BENCHMARKS.md.
scenarios! {
    /// First run: named `hyst(rate(supply_v, 660), 0.0065)`, 1.25× where the truth form reaches
    /// 1.09× (the test's bound is 1.2× the limit; the 1.2× of the floor is missed).
    a_relay_on_an_inputs_rate: "relay on an input's rate", Qma, [Poly], 111, "hyst(rate(supply_v, 600), 0.01)", 6.0, true, 0.25;
    /// First run: named `clamp(rate(supply_v, 300), -0.00878, 0.00982)`, 1.10× (limit 1.08×).
    a_saturating_input_rate: "saturating input rate", Qma, [Poly], 112, "clamp(rate(supply_v, 300), -0.01, 0.01)", 6.0, true, 0.25;
    /// First run: "cannot tell" (a relay on T through a 100 s lag, no better than its placebos),
    /// 7.60× with nothing added, where the truth form reaches 0.97× (told: 0.97×). Since the
    /// compositions' refit slots go by the placebo leg's statistic (`confirm`): named `supply_v`
    /// (the verification run +0.2 %), 7.58×.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_relay_on_an_input_times_a_temperature_rate: "relay on an input × temperature rate", Qma, [Poly], 113, "hyst(supply_v - 28.2, 0.2) * rate(t_qma_c)", 6.0, false, 0.25;
    /// First run: named the two gradients (a listed family; the verification run 11 % better),
    /// 6.11× where the truth form reaches 1.06× (told: 1.06×): the relay on the lagged gradient
    /// led the compositions (+193.5 nats) but was no better than its placebos. With the gradient
    /// shifted: named as one, `hyst(lag(t_anode_c - t_shell_c, 960) - 1.11, 0.15)` (+440.6
    /// nats, placebos +10.7), the lag 1.6× and the band a third of the truth's: 1.75×.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_relay_on_a_lagged_gradient: "relay on a lagged gradient", Rlg, [Poly], 114, "hyst(lag(t_anode_c - t_shell_c, 600) - 1, 0.5)", 6.0, false, 0.25;
    /// First run: none, 8.23× where the truth form reaches 1.08×: the truth's own shape led (+486
    /// nats, beating its placebos), but the joint model's refits over T and the heater predicted
    /// every held-out block worse (−39.8 %: the heater's range differs block to block), where the
    /// user's fit with it chooses the additive structure. With the refits offering the additive
    /// structure where the features read an input (the blocks' refits pinned to it): named
    /// exactly, 1.21× (told: 1.21×), but a 1,000-unit `calibrate` took 8 min 47 s: not kept.
    /// The second look in the additive structure (`confirm::additive`) reaches it, but its
    /// additive blocks do worse still (−67 % against the base's better structure): none. Since
    /// the placebos' noise is re-read from each model's residual (`placebo`): named on fresh
    /// seeds (+1000: 1.71×; +7000, held out: 1.19×); here still "cannot tell", its joint refits
    /// predicting the blocks 39.8 % worse.
    #[ignore = "a known miss: run with --ignored to measure it"]
    a_kink_in_a_second_input: "kink in a second input", Qma, [Poly], 115, "abs(heater_v - 12.1)", 6.0, true, 0.25;
}

/// Two of the sensor's own effects hidden at once from a model of the rest, which stand in for
/// each other in part: the rate of the mean temperature and the thermal gradients of the RLG (a
/// gradient follows the rate during a ramp), or the rate and the Shupe term of the IFOG. Each alone
/// made the verification run worse on the RLG preset (see [`tcomp_discover::confirm::together`]).
/// Returns the verdict, the ratio after adding what it names, the one before, the least-squares
/// limit of the truth form, and the text.
fn two_hidden(
    sensor: SensorKind,
    hidden: [EffectKind; 2],
    seed: u64,
) -> (Verdict, f64, f64, f64, String) {
    let case = base_case(
        presets::with_effects(sensor, &[EffectKind::Poly, hidden[0], hidden[1]])
            .unwrap()
            .with_seed(seed),
        &hidden,
    );
    let o = run(&case);
    let features = if o.diagnosis.verdict == Verdict::MissingEffect {
        o.top().candidate().applied_to(&case.base)
    } else {
        case.base.clone()
    };
    let after = after_ratio(&case, &features);
    let before = after_ratio(&case, &case.base);
    let limit = limit_ratio(&case);
    let text = format!(
        "{sensor:?} seed {seed}, {hidden:?} hidden from {:?}\n{}  after {features:?}: \
         {after:.2}× the floor (before {before:.2}×, limit {limit:.2}×)",
        case.base, o.text
    );
    println!("{text}");
    println!(
        "TWO-HIDDEN {sensor:?} {seed}: {:?}, {after:.2}× (before {before:.2}×, limit {limit:.2}×)",
        o.diagnosis.verdict
    );
    (o.diagnosis.verdict, after, before, limit, text)
}

/// Asserts what a diagnosis of two missing effects owes the user: it says something is missing
/// (a named effect or "cannot tell", never "none"), and what it names lowers the verification
/// run to 1.2× the floor, or 1.2× the least-squares limit when that stays above the floor.
fn check_two_hidden(sensor: SensorKind, hidden: [EffectKind; 2], seed: u64) {
    let (verdict, after, before, limit, text) = two_hidden(sensor, hidden, seed);
    assert_ne!(verdict, Verdict::None, "{text}");
    if verdict == Verdict::MissingEffect {
        assert!(after < before, "{text}");
        assert!(after <= AFTER_TARGET * limit.max(1.0), "{text}");
    }
}

/// RLG seeds seen while the unions were built (302 the gradients and the rate of a gradient named
/// together, 1.02× where the limit is 1.01×; seed 0 is the next test).
#[test]
fn two_effects_missing_at_once() {
    check_two_hidden(
        SensorKind::Rlg,
        [EffectKind::Rate, EffectKind::Gradient],
        302,
    );
}

/// RLG seed 0, seen while the unions were built: "cannot tell", 3.95× with nothing added, while
/// the two thermometer gradients failed their placebos at the base's noise (1.1 against 2.6).
/// Since the placebos' noise is re-read from each model's residual (one Cochrane–Orcutt step,
/// `placebo`): the two gradients pass them (43.0 against 26.9) and are named, and the
/// verification run gets 49 % worse, 5.90× — a wrong effect: they carry the missing rate on
/// this run's ramps (held-out blocks −77 %) and not on the verification run's.
#[test]
#[ignore = "a known miss: run with --ignored to measure it"]
fn two_effects_missing_at_once_on_a_run_whose_gradients_carry_the_rate() {
    check_two_hidden(SensorKind::Rlg, [EffectKind::Rate, EffectKind::Gradient], 0);
}

/// Held out from the design of the unions: fresh RLG seeds, and the IFOG's rate and Shupe term.
/// Measured once (figures in BENCHMARKS.md): RLG 303–305 the gradients and the rate of a gradient
/// named together, 1.04×, 0.99×, 1.06× (limits 1.03×, 1.08×, 1.01×); IFOG 306 and 307 the true
/// pair named together, 1.39× where the limit is 1.12× and 1.12× (limit 1.02×) — on 306 the
/// trainer's fit of the true features falls short (issue 25's side), and the test's bound fails.
#[test]
#[ignore = "held-out scenarios, measured once: run with --ignored"]
fn two_effects_missing_at_once_on_fresh_runs() {
    let mut failed = Vec::new();
    let cases = [
        (
            SensorKind::Rlg,
            [EffectKind::Rate, EffectKind::Gradient],
            303,
        ),
        (
            SensorKind::Rlg,
            [EffectKind::Rate, EffectKind::Gradient],
            304,
        ),
        (
            SensorKind::Rlg,
            [EffectKind::Rate, EffectKind::Gradient],
            305,
        ),
        (SensorKind::Ifog, [EffectKind::Rate, EffectKind::Shupe], 306),
        (SensorKind::Ifog, [EffectKind::Rate, EffectKind::Shupe], 307),
    ];
    for (sensor, hidden, seed) in cases {
        let r = std::panic::catch_unwind(|| check_two_hidden(sensor, hidden, seed));
        if r.is_err() {
            failed.push(format!("{sensor:?} {seed}"));
        }
    }
    assert!(failed.is_empty(), "failed: {failed:?}");
}
