//! Numbers as an engineer reads them: plain notation (`0.09144`, never `9.144e-2`), four
//! significant digits, the unit appended; and one sign convention for changes: a change is
//! `100·(after/before − 1)`, so "-35 %" means the residual fell by 35 %.
//!
//! Why one module: the tables of `eval`, `diagnose`, `compare`, the demo's narrative and the
//! report's tables and axes each formatted numbers their own way (`{:.4e}` here, `{:.4}` there), so
//! one line could mix `9.144e-2` and `0.0914`, and "improvement" and "change" had opposite signs.
//! It lives in the trainer's library so the libraries' own sentences (discovery's verdicts) and the
//! command line's tables format alike; the CLI re-exports it as `render::num`.
//! Every figure a person reads goes through [`num`] (or [`plain`] where the unit is a column
//! header), every change through [`change_pct`] and [`pct`]; a value the user gave (an option's
//! value named in an error, a bound of its range) through [`exact`], which does not round.

/// Significant digits of a figure.
pub const SIG: usize = 4;

/// Most decimals written (a smaller magnitude prints as `0`).
const MAX_DECIMALS: usize = 20;

/// `v` in plain notation with `sig` significant digits, trailing zeros dropped; an integer part
/// longer than `sig` digits is written in full (`17099`), a non-finite value as `n/a`.
pub fn plain(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i64;
    let decimals = (sig.max(1) as i64 - 1 - mag).clamp(0, MAX_DECIMALS as i64) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    // Rounding may leave "-0".
    if s.trim_start_matches('-') == "0" {
        "0".into()
    } else {
        s
    }
}

/// `v` with [`SIG`] significant digits and its unit (`0.09144 deg/h`); no unit, no space.
pub fn num(v: f64, unit: &str) -> String {
    with_unit(plain(v, SIG), unit)
}

/// `v` exactly, as a user would write it back in a flag or a spec key: every digit Rust needs to
/// read it back (`0.1`, `1234.5678`), in scientific notation outside [10⁻⁴, 10⁹) (`1e-300` rather
/// than three hundred zeros); `NaN` and `inf` as Rust writes them. Unlike [`num`], which rounds a
/// figure to [`SIG`] digits for reading, this names a value given (an option's value in an error,
/// a bound), which must not be rounded.
pub fn exact(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// `text` followed by `unit` (a space between; nothing when the unit is empty).
pub fn with_unit(text: String, unit: &str) -> String {
    if unit.is_empty() {
        text
    } else {
        format!("{text} {unit}")
    }
}

/// An axis tick: as many digits as the tick step `step` needs, so neighbouring ticks differ (a
/// tick within a millionth of a step of zero is zero, not a rounding residue).
pub fn tick(v: f64, step: f64) -> String {
    if !(step.is_finite() && step > 0.0) {
        return plain(v, SIG);
    }
    if v.abs() < 1e-6 * step {
        return "0".into();
    }
    let digits = v.abs().log10().floor() - step.log10().floor() + 1.0;
    plain(v, digits.clamp(1.0, 15.0) as usize)
}

/// The change from `before` to `after` in percent, negative when the figure fell; `None` when
/// `before` is not a positive figure (no data, or nothing to fall from).
pub fn change_pct(before: f64, after: f64) -> Option<f64> {
    (before.is_finite() && after.is_finite() && before > 0.0)
        .then(|| 100.0 * (after / before - 1.0))
}

/// A change in percent, signed, one decimal below 100 % (`-35.2 %`, `+4.1 %`, `0 %`); `n/a`
/// for no change measurable.
pub fn pct(change: Option<f64>) -> String {
    match change {
        Some(p) if p.is_finite() => {
            let s = signed(p, if p.abs() < 100.0 { 1 } else { 0 });
            format!("{s} %")
        }
        _ => "n/a".into(),
    }
}

/// `v` with `decimals` decimals and its sign (`+0.3`, `-1.2`), trailing zeros dropped; `0` when
/// it rounds to zero. For differences such as a change or a Δ log evidence.
pub fn signed(v: f64, decimals: usize) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let s = format!("{v:+.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s.trim_start_matches(['+', '-']) == "0" {
        "0".into()
    } else {
        s
    }
}

/// The unit a column's name ends in, by the measurement CSV's naming convention (`gyro_x_rad_s`,
/// `accel_m_s2`, `gyro_dph`, `accel_ug`, `temp_imu_C`); `None` when the name has no known suffix.
pub fn unit_of_column(name: &str) -> Option<&'static str> {
    const SUFFIXES: [(&str, &str); 12] = [
        ("_rad_s", "rad/s"),
        ("_m_s2", "m/s²"),
        ("_dph", "deg/h"),
        ("_dps", "deg/s"),
        ("_ug", "µg"),
        ("_mg", "mg"),
        ("_g", "g"),
        ("_c", "°C"),
        ("_k", "K"),
        ("_v", "V"),
        ("_t", "T"),
        ("_s", "s"),
    ];
    let lower = name.to_ascii_lowercase();
    SUFFIXES
        .iter()
        .find(|(suffix, _)| lower.ends_with(suffix) && lower.len() > suffix.len())
        .map(|(_, unit)| *unit)
}

/// The unit to show: `given` when not empty, else the one `column`'s name carries, else empty.
pub fn unit_or_column(given: &str, column: &str) -> String {
    if given.trim().is_empty() {
        unit_of_column(column).unwrap_or("").to_string()
    } else {
        given.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_notation_with_four_significant_digits() {
        assert_eq!(plain(0.091_441, SIG), "0.09144");
        assert_eq!(plain(9.144e-2, SIG), plain(0.09144, SIG));
        assert_eq!(plain(17_099.4, SIG), "17099");
        assert_eq!(plain(-1.5e-5, SIG), "-0.000015");
        assert_eq!(plain(2.0, SIG), "2");
        assert_eq!(plain(9.99996, SIG), "10");
        assert_eq!(plain(-0.0, SIG), "0");
        assert_eq!(plain(f64::NAN, SIG), "n/a");
        assert!(!plain(1.234e-9, SIG).contains('e'));
        assert_eq!(num(0.0297, "deg/h"), "0.0297 deg/h");
        assert_eq!(num(3.0, ""), "3");
    }

    #[test]
    fn exact_keeps_every_digit_and_writes_extremes_in_scientific_notation() {
        assert_eq!(exact(0.1), "0.1");
        assert_eq!(exact(1234.5678), "1234.5678");
        assert_eq!(exact(1e7), "10000000");
        assert_eq!(exact(1e-300), "1e-300");
        assert_eq!(exact(-2.5e10), "-2.5e10");
        assert_eq!(exact(0.0), "0");
        assert_eq!(exact(f64::NAN), "NaN");
    }

    #[test]
    fn ticks_tell_neighbours_apart() {
        assert_eq!(tick(20.5, 0.5), "20.5");
        assert_eq!(tick(1000.0, 200.0), "1000");
        assert_eq!(tick(0.0012, 0.0002), "0.0012");
        assert_ne!(tick(0.0012, 0.0001), tick(0.0013, 0.0001));
        assert_eq!(tick(1.3e-17, 0.05), "0");
    }

    #[test]
    fn a_fall_is_negative() {
        assert_eq!(pct(change_pct(0.0914, 0.0594)), "-35 %");
        assert_eq!(pct(change_pct(0.04222, 0.03153)), "-25.3 %");
        assert_eq!(pct(Some(1e-14)), "0 %");
        assert_eq!(pct(Some(250.4)), "+250 %");
        assert_eq!(signed(-0.04, 1), "0");
        assert_eq!(signed(0.26, 1), "+0.3");
        assert_eq!(pct(change_pct(1.0, 1.25)), "+25 %");
        assert_eq!(pct(change_pct(0.0, 1.0)), "n/a");
        assert_eq!(pct(change_pct(2.0, 2.0)), "0 %");
    }

    #[test]
    fn units_from_column_names() {
        assert_eq!(unit_of_column("gyro_x_rad_s"), Some("rad/s"));
        assert_eq!(unit_of_column("accel_z_m_s2"), Some("m/s²"));
        assert_eq!(unit_of_column("gyro_dph"), Some("deg/h"));
        assert_eq!(unit_of_column("accel_ug"), Some("µg"));
        assert_eq!(unit_of_column("temp_lsm6dsm_C"), Some("°C"));
        assert_eq!(unit_of_column("chunk_id"), None);
        assert_eq!(unit_or_column("", "gyro_dph"), "deg/h");
        assert_eq!(unit_or_column("mdeg/h", "gyro_dph"), "mdeg/h");
    }
}
