//! The reference case for fit timings, shared by the `fit` bench and the `compare_rows`
//! example: the `rlg` preset's training run, features T = mean of the three thermometers, rate(T)
//! and the two gradients against the shell, `bayes` with 32 centers.

use tcomp_train::FitOptions;

/// Fit options of the reference case.
pub fn options() -> FitOptions {
    let mut o = FitOptions::new(
        "gyro_dph",
        &[
            "T",
            "rate(T)",
            "t_anode_c - t_shell_c",
            "t_cathode_c - t_shell_c",
        ],
    );
    o.spec
        .signals
        .push("T = mean(t_anode_c, t_cathode_c, t_shell_c)".into());
    o.reference = Some("ref_dph".into());
    o.centers = Some(32);
    o
}
