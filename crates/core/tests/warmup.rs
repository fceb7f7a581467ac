//! `warmup(tau_s)`: a function of the time since power-on alone — compiled from the table,
//! evaluated to `e^(−t_on/τ)` over hours of f32 steps, carried exactly across gaps (even those that
//! restart the filters), printed and read back, and stamped as blob format version 2.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_core::blob::OLDEST_FORMAT_VERSION;
use tcomp_core::testing::example_model;
use tcomp_core::{Model, Op, ParseErrorKind, Program, ProgramBuilder, ProgramState};

fn compile(text: &'static str) -> Result<Program<'static, 16, 4>, ParseErrorKind> {
    let mut b = ProgramBuilder::<16, 4>::new();
    b.feature(text).map_err(|e| e.kind)?;
    Ok(b.finish().unwrap())
}

#[test]
fn warmup_compiles_from_the_table() {
    let p = compile("warmup(600)").unwrap();
    assert_eq!(
        p.nodes.as_slice(),
        &[Op::Warmup {
            slot: 0,
            tau_s: 600.0
        }]
    );
    assert!(
        p.inputs.is_empty(),
        "a function of time alone reads no column"
    );
    assert_eq!(p.format_version(), 2);
    let p = compile("warmup(2 * 300) * x").unwrap();
    assert_eq!(p.inputs.as_slice(), &["x"]);
    assert_eq!(compile("warmup(x)"), Err(ParseErrorKind::ConstantRequired));
    assert_eq!(compile("warmup(0)"), Err(ParseErrorKind::BadParameter));
    assert_eq!(compile("warmup(-5)"), Err(ParseErrorKind::BadParameter));
    assert_eq!(
        compile("warmup(600, 1)"),
        Err(ParseErrorKind::WrongArgCount)
    );
    assert!(compile("warmup()").is_err());
}

/// Two hours at 200 Hz in f32: the clock's compensated sum keeps `t_on` to rounding, where a plain
/// f32 sum of 5 ms steps would be off by seconds (tested against one).
#[test]
fn warmup_is_exp_of_the_time_since_power_on_in_f32() {
    let p = compile("warmup(600)").unwrap();
    let mut st = ProgramState::<16>::new();
    let dt = 0.005f32;
    let mut naive = 0.0f32;
    let mut worst = 0.0f64;
    for n in 0..1_440_000u32 {
        st.step(&p, &[], dt).unwrap();
        if n > 0 {
            naive += dt;
        }
        let t = f64::from(n) * f64::from(dt);
        let want = (-t / 600.0).exp();
        worst = worst.max((f64::from(st.value(0)) - want).abs());
    }
    assert!(worst < 2e-6, "worst error {worst}");
    let t_end = 1_439_999.0 * f64::from(dt);
    assert!(
        (f64::from(naive) - t_end).abs() > 1.0,
        "a plain sum drifts (the test can tell): {naive} vs {t_end}"
    );
}

#[test]
fn warmup_starts_at_the_time_on_given_and_counts_every_gap() {
    let mut b = ProgramBuilder::<16, 4>::new();
    b.feature("warmup(600)").unwrap();
    b.feature("lag(x, 10)").unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<16>::new();
    st.set_time_on(120.0);
    st.step(&p, &[1.0], 1.0).unwrap();
    let w = |st: &ProgramState<16>| f64::from(st.value(p.features[0] as usize));
    assert!((w(&st) - (-120.0f64 / 600.0).exp()).abs() < 1e-6);
    st.step(&p, &[1.0], 1.0).unwrap();
    // A gap far longer than 5 × the lag's τ: the lag restarts, the clock counts the gap.
    assert!(tcomp_core::stream::gap_resets(&p, 1000.0));
    st.step_gap(&p, &[5.0], 1000.0).unwrap();
    assert_eq!(st.value(p.features[1] as usize), 5.0, "the lag restarted");
    assert!(
        (w(&st) - (-1121.0f64 / 600.0).exp()).abs() < 1e-6,
        "{}",
        w(&st)
    );
    // A reset (a new model on the channel) keeps the time on of the start.
    st.reset();
    st.step(&p, &[1.0], 1.0).unwrap();
    assert!((w(&st) - (-120.0f64 / 600.0).exp()).abs() < 1e-6);
}

#[test]
fn warmup_prints_and_reads_back() {
    use tcomp_core::expr;
    let e = expr::warmup(1200.0) * expr::name("T");
    let text = e.to_string();
    assert_eq!(text, "warmup(1200) * T");
    let p = compile(Box::leak(text.into_boxed_str())).unwrap();
    assert_eq!(
        p.nodes[0],
        Op::Warmup {
            slot: 0,
            tau_s: 1200.0
        }
    );
}

#[test]
fn a_model_using_warmup_is_a_version_2_blob_and_round_trips() {
    let base = example_model::<64, 8, 48>(8, 1);
    let mut b = ProgramBuilder::<48, 8>::new();
    b.line("T = mean(t_anode_c, t_cathode_c, t_shell_c)")
        .unwrap();
    for f in ["T", "rate(T)", "warmup(900)", "t_cathode_c - t_shell_c"] {
        b.feature(f).unwrap();
    }
    let program = b.finish().unwrap();
    let m = Model::new(
        base.meta,
        program,
        base.ranges.clone(),
        base.rbf.clone(),
        base.residual,
    );
    assert_eq!(m.version, 2);
    let mut buf = vec![0u8; 8192];
    let n = m.encode(&mut buf).unwrap();
    // A reader of version 1 only (`reads_version` was `1..=1`) refuses this byte by number.
    assert_eq!(buf[4], 2);
    assert!(buf[4] as u16 > OLDEST_FORMAT_VERSION);
    let back = Model::<64, 8, 48>::decode(&buf[..n]).unwrap();
    assert_eq!(back, m);
    // The same model without warmup is version 1, as every blob before it.
    assert_eq!(base.version, 1);
}
