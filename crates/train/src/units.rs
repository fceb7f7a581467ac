//! Units parsed, not compared as text: `m/s2`, `m/s^2`, `m s-2` and `m·s⁻²` are one unit, `deg/h`,
//! `°/h` and `dph` are one unit, and `deg/s` against `rad/s` is the same quantity with a factor.
//!
//! Why a small table rather than a crate: the unit crates (`uom`, `dimensioned`) check units at
//! compile time from Rust types and parse no unit text; the text parsers on crates.io target SI
//! with mass and amount of substance, not the gyro and accelerometer units of inertial navigation
//! (`dph`, `µg`, `arcsec`, `LSB`), and `g` there is the gram. Here the dimensions are those a
//! sensor channel has — length, time, angle, counts, volts, temperature — `g` is standard gravity
//! (9.80665 m/s², so `mg` is a milli-g and `ug`/`µg` a micro-g), and one [`Unit`] is a factor times
//! a product of powers of these.
//!
//! Grammar: terms separated by `/`, `*`, `·`, `.` or spaces; a term is an optional SI prefix (`n`,
//! `u`/`µ`/`μ`, `m`, `k`) and a unit name, then an optional exponent (`2`, `^2`, `-2`, `^-2`, `²`,
//! `⁻¹`); `/` inverts the one term after it. A unit name is matched whole before a prefix is tried,
//! so `min` is a minute and `mrad` a milliradian.

use std::fmt;

/// Dimensions: length, time, angle, count, volt, temperature.
const DIMS: usize = 6;

/// A parsed unit: `factor` times the base units raised to `dims`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    /// The value of one of this unit in base units (m, s, rad, count, V, K).
    pub factor: f64,
    /// Exponents of length, time, angle, count, volt and temperature.
    pub dims: [i8; DIMS],
}

/// Why a unit does not parse: the text, the 1-based character where the trouble starts, and what.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("unit `{text}`, character {at}: {what}")]
pub struct UnitError {
    /// The unit as given.
    pub text: String,
    /// 1-based character.
    pub at: usize,
    /// What is wrong.
    pub what: String,
}

/// How two units relate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Relation {
    /// The same unit (perhaps spelt differently).
    Same,
    /// The same quantity: one of the first is `factor` of the second.
    Scaled(f64),
    /// Different quantities.
    Different,
}

const G0: f64 = 9.806_65;
const DEG: f64 = std::f64::consts::PI / 180.0;

/// The unit names: spellings, factor, dimensions. Prefixes apply to those marked `true`.
const NAMES: &[(&[&str], f64, [i8; DIMS], bool)] = &[
    (&["m", "meter", "metre"], 1.0, [1, 0, 0, 0, 0, 0], true),
    (&["s", "sec"], 1.0, [0, 1, 0, 0, 0, 0], true),
    (&["min"], 60.0, [0, 1, 0, 0, 0, 0], false),
    (&["h", "hr", "hour"], 3600.0, [0, 1, 0, 0, 0, 0], false),
    (&["Hz"], 1.0, [0, -1, 0, 0, 0, 0], true),
    (&["rad"], 1.0, [0, 0, 1, 0, 0, 0], true),
    (&["deg", "°"], DEG, [0, 0, 1, 0, 0, 0], false),
    (&["arcmin"], DEG / 60.0, [0, 0, 1, 0, 0, 0], false),
    (&["arcsec"], DEG / 3600.0, [0, 0, 1, 0, 0, 0], false),
    (
        &["rev"],
        2.0 * std::f64::consts::PI,
        [0, 0, 1, 0, 0, 0],
        false,
    ),
    (&["dph"], DEG / 3600.0, [0, -1, 1, 0, 0, 0], false),
    (&["dps"], DEG, [0, -1, 1, 0, 0, 0], false),
    (&["g", "gee"], G0, [1, -2, 0, 0, 0, 0], true),
    (
        &["LSB", "lsb", "count", "counts", "cnt"],
        1.0,
        [0, 0, 0, 1, 0, 0],
        false,
    ),
    (&["V"], 1.0, [0, 0, 0, 0, 1, 0], true),
    (&["K", "degC", "°C", "C"], 1.0, [0, 0, 0, 0, 0, 1], false),
    (&["ppm"], 1e-6, [0; DIMS], false),
    (&["%"], 1e-2, [0; DIMS], false),
    (&["1"], 1.0, [0; DIMS], false),
];

const PREFIXES: &[(&str, f64)] = &[
    ("n", 1e-9),
    ("u", 1e-6),
    ("µ", 1e-6),
    ("μ", 1e-6),
    ("m", 1e-3),
    ("k", 1e3),
];

/// A name's factor and dimensions, with an optional prefix.
fn lookup(name: &str) -> Option<(f64, [i8; DIMS])> {
    let whole = |n: &str| NAMES.iter().find(|(s, ..)| s.contains(&n));
    if let Some((_, f, d, _)) = whole(name) {
        return Some((*f, *d));
    }
    PREFIXES.iter().find_map(|(p, pf)| {
        let rest = name.strip_prefix(p)?;
        let (_, f, d, prefixable) = whole(rest)?;
        prefixable.then_some((pf * f, *d))
    })
}

/// A superscript digit or minus as its plain character.
fn plain_superscript(c: char) -> Option<char> {
    Some(match c {
        '⁰' => '0',
        '¹' => '1',
        '²' => '2',
        '³' => '3',
        '⁴' => '4',
        '⁵' => '5',
        '⁶' => '6',
        '⁷' => '7',
        '⁸' => '8',
        '⁹' => '9',
        '⁻' => '-',
        _ => return None,
    })
}

/// Parses a unit; an empty text is refused (no unit is no unit, not a dimensionless one).
pub fn parse(text: &str) -> Result<Unit, UnitError> {
    let err = |at: usize, what: String| UnitError {
        text: text.to_string(),
        at: at + 1,
        what,
    };
    let chars: Vec<char> = text.chars().collect();
    if text.trim().is_empty() {
        return Err(err(0, "empty".into()));
    }
    let mut unit = Unit {
        factor: 1.0,
        dims: [0; DIMS],
    };
    let mut i = 0usize;
    let mut invert_next = false;
    let mut terms = 0usize;
    while i < chars.len() {
        let c = chars.get(i).copied().unwrap_or(' ');
        if c == '/' {
            if invert_next || terms == 0 {
                return Err(err(i, "`/` with no unit before it".into()));
            }
            invert_next = true;
            i += 1;
            continue;
        }
        if matches!(c, ' ' | '*' | '·' | '.') {
            i += 1;
            continue;
        }
        // A name: letters, `°`, `%`, or the digit 1 alone.
        let start = i;
        if c == '1' {
            i += 1;
        } else {
            while chars
                .get(i)
                .is_some_and(|c| c.is_alphabetic() || matches!(c, '°' | '%' | 'µ' | 'μ'))
            {
                i += 1;
            }
        }
        if i == start {
            return Err(err(i, format!("`{c}` where a unit name should be")));
        }
        let name: String = chars.get(start..i).unwrap_or(&[]).iter().collect();
        let Some((f, d)) = lookup(&name) else {
            return Err(err(
                start,
                format!(
                    "`{name}` is not a unit tcomp knows (m, s, min, h, Hz, rad, deg or °, arcsec, \
                     dph, g for standard gravity, LSB, V, degC, ppm, with the prefixes n, u or µ, \
                     m, k)"
                ),
            ));
        };
        // The exponent.
        if chars.get(i) == Some(&'^') {
            i += 1;
        }
        let exp_start = i;
        let mut exp = String::new();
        while let Some(&c) = chars.get(i) {
            let c = plain_superscript(c).unwrap_or(c);
            if c.is_ascii_digit() || (c == '-' && exp.is_empty()) {
                exp.push(c);
                i += 1;
            } else {
                break;
            }
        }
        let e: i8 = if exp.is_empty() {
            if i > exp_start || chars.get(exp_start.wrapping_sub(1)) == Some(&'^') {
                return Err(err(exp_start, "`^` with no exponent after it".into()));
            }
            1
        } else {
            exp.parse()
                .ok()
                .filter(|e: &i8| *e != 0)
                .ok_or_else(|| err(exp_start, format!("`{exp}` is not an exponent")))?
        };
        let e = if invert_next { -e } else { e };
        invert_next = false;
        unit.factor *= f.powi(i32::from(e));
        for (u, x) in unit.dims.iter_mut().zip(d) {
            *u = u.saturating_add(x.saturating_mul(e));
        }
        terms += 1;
    }
    if invert_next {
        return Err(err(chars.len(), "`/` with no unit after it".into()));
    }
    Ok(unit)
}

/// How `a` relates to `b` (both parsed).
pub fn relate(a: &str, b: &str) -> Result<Relation, UnitError> {
    let (ua, ub) = (parse(a)?, parse(b)?);
    if ua.dims != ub.dims {
        return Ok(Relation::Different);
    }
    let ratio = ua.factor / ub.factor;
    Ok(if (ratio - 1.0).abs() <= 1e-12 {
        Relation::Same
    } else {
        Relation::Scaled(ratio)
    })
}

impl fmt::Display for Relation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Same => write!(f, "the same unit"),
            Self::Scaled(k) => write!(
                f,
                "the same quantity scaled by {}",
                crate::num::plain(*k, 9)
            ),
            Self::Different => write!(f, "different quantities"),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic)]
mod tests {
    use super::*;

    #[test]
    fn one_unit_many_spellings() {
        for a in ["m/s2", "m/s^2", "m s-2", "m·s⁻²", "m*s^-2", "m/s/s"] {
            assert_eq!(relate(a, "m/s^2"), Ok(Relation::Same), "{a}");
        }
        for a in ["deg/h", "°/h", "dph", "deg h-1"] {
            assert_eq!(relate(a, "deg/h"), Ok(Relation::Same), "{a}");
        }
        assert_eq!(relate("ug", "µg"), Ok(Relation::Same));
        assert_eq!(relate("mrad", "rad"), Ok(Relation::Scaled(1e-3)));
    }

    #[test]
    fn commensurable_units_have_their_factor() {
        let Ok(Relation::Scaled(k)) = relate("deg/s", "rad/s") else {
            panic!("deg/s and rad/s are one quantity");
        };
        assert!((k - std::f64::consts::PI / 180.0).abs() < 1e-15);
        let Ok(Relation::Scaled(k)) = relate("ug", "m/s^2") else {
            panic!("µg is an acceleration");
        };
        assert!((k - 9.80665e-6).abs() < 1e-18);
        assert_eq!(relate("deg/h", "m/s^2"), Ok(Relation::Different));
        assert_eq!(relate("min", "s"), Ok(Relation::Scaled(60.0)));
    }

    #[test]
    fn what_does_not_parse_is_named_with_its_place() {
        let e = parse("furlong/fortnight").unwrap_err();
        assert_eq!(e.at, 1);
        assert!(e.to_string().contains("`furlong` is not a unit"), "{e}");
        let e = parse("m/").unwrap_err();
        assert_eq!(e.at, 3);
        let e = parse("m/s^").unwrap_err();
        assert!(e.what.contains("no exponent"), "{e}");
        assert!(parse("").is_err() && parse("/s").is_err() && parse("m#s").is_err());
    }
}
