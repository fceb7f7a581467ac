//! The user's program recovered from a blob, and the name-level edits candidates make to it.
//!
//! Why: a blob carries the program the trainer *stored*, which may hold signals the user never
//! wrote — the cubic basis `bayes` may choose appends `Tclamped = clamp(T, lo, hi)`, `sq(Tclamped)`
//! and `Tclamped * sq(Tclamped)`, and `poly3` rewrites its whole program around `Tclamped`. A
//! diagnosis that built candidates from those (`rate(Tclamped, 240)`) would print expressions that
//! `tcomp fit --feature` refuses, because the user's command line has no `Tclamped`. So the
//! diagnosis works on the program as the user wrote it: the internal signal removed, the cubic's
//! own features dropped (the trainer adds them again when it chooses the cubic), and `Tclamped`
//! as a feature read back as the temperature it clamps.
//!
//! The edits are at the level of names: whether an expression uses a name, and the expression
//! with every use of a name replaced by another expression (a lag replacing its thermometer).
//! A replacement is always a call or a name, which binds tighter than any operator, so putting it
//! where the name stood never needs parentheses: the result compiles to the tree with the name's
//! leaves replaced, and nothing else changes.

use tcomp_core::expr::Expr;
use tcomp_train::features::FeatureSpec;
use tcomp_train::poly3::SIGNAL as CLAMPED;

/// One token of an expression's text: a name (not followed by `(`) or any other run of text.
enum Token<'a> {
    Name(&'a str),
    Other(&'a str),
}

/// Splits `text` into names and the text between them (number literals, operators, function
/// names, spaces), so that joining the tokens gives `text` back.
fn tokens(text: &str) -> Vec<Token<'_>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let (mut i, mut other) = (0, 0);
    while i < b.len() {
        let c = b.get(i).copied().unwrap_or(b' ');
        if c.is_ascii_digit() || c == b'.' {
            // A number literal, exponent included (`2e-3` holds no name `e`).
            i += 1;
            while let Some(&d) = b.get(i) {
                let exp_sign = (d == b'+' || d == b'-')
                    && matches!(b.get(i.wrapping_sub(1)), Some(b'e' | b'E'));
                if d.is_ascii_alphanumeric() || d == b'.' || exp_sign {
                    i += 1;
                } else {
                    break;
                }
            }
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while b
                .get(i)
                .is_some_and(|d| d.is_ascii_alphanumeric() || *d == b'_')
            {
                i += 1;
            }
            let next = text
                .get(i..)
                .and_then(|r| r.trim_start().chars().next())
                .unwrap_or(' ');
            if next != '(' {
                if other < start {
                    out.push(Token::Other(text.get(other..start).unwrap_or("")));
                }
                out.push(Token::Name(text.get(start..i).unwrap_or("")));
                other = i;
            }
        } else {
            i += 1;
        }
    }
    if other < text.len() {
        out.push(Token::Other(text.get(other..).unwrap_or("")));
    }
    out
}

/// Whether `expr` uses the name `name`.
pub fn uses(expr: &str, name: &str) -> bool {
    tokens(expr)
        .iter()
        .any(|t| matches!(t, Token::Name(n) if *n == name))
}

/// `expr` with every use of `name` replaced by `by` (a call or a name: see the module doc).
pub fn replace(expr: &str, name: &str, by: &Expr) -> String {
    let by = by.to_string();
    let mut out = String::with_capacity(expr.len() + by.len());
    for t in tokens(expr) {
        match t {
            Token::Name(n) if n == name => out.push_str(&by),
            Token::Name(s) | Token::Other(s) => out.push_str(s),
        }
    }
    out
}

/// The name a signal line `NAME = expr` defines.
pub fn signal_name(line: &str) -> &str {
    line.split_once('=').map_or("", |(n, _)| n.trim())
}

/// The first argument of `clamp(x, lo, hi)` (the text of `x`), if `text` is such a call.
fn clamp_argument(text: &str) -> Option<&str> {
    let inner = text.trim().strip_prefix("clamp")?.trim_start();
    let inner = inner.strip_prefix('(')?.strip_suffix(')')?;
    let mut depth = 0i32;
    for (i, c) in inner.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => return inner.get(..i).map(str::trim),
            _ => {}
        }
    }
    None
}

/// The program as the user wrote it (see the module doc): the cubic's internal signal removed,
/// its features dropped, and `Tclamped` alone read back as the temperature it clamps.
pub fn user_spec(stored: &FeatureSpec) -> FeatureSpec {
    let clamped = stored
        .signals
        .iter()
        .find(|s| signal_name(s) == CLAMPED)
        .and_then(|s| s.split_once('=').and_then(|(_, e)| clamp_argument(e)))
        .map(str::to_string);
    let Some(clamped) = clamped else {
        return stored.clone();
    };
    let mut features: Vec<String> = Vec::new();
    for f in &stored.features {
        if f.trim() == CLAMPED {
            if !features.contains(&clamped) {
                features.push(clamped.clone());
            }
        } else if !uses(f, CLAMPED) && !features.contains(f) {
            features.push(f.clone());
        }
    }
    FeatureSpec {
        signals: stored
            .signals
            .iter()
            .filter(|s| signal_name(s) != CLAMPED)
            .cloned()
            .collect(),
        features,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tcomp_core::expr;

    #[test]
    fn names_are_found_and_replaced_but_not_in_numbers_or_calls() {
        assert!(uses("T * rate(T)", "T"));
        assert!(!uses("rate(t_a) + 2e-3", "e"));
        assert!(!uses("lag(x, 1e3)", "lag"));
        assert!(!uses("T2 - t", "T"));
        let by = expr::lag(expr::name("T"), 1800.0);
        assert_eq!(replace("T", "T", &by), "lag(T, 1800)");
        assert_eq!(
            replace("T * rate(T, 240) + 1.5e-2", "T", &by),
            "lag(T, 1800) * rate(lag(T, 1800), 240) + 1.5e-2"
        );
        assert_eq!(replace("sq(T2 - T)", "T", &by), "sq(T2 - lag(T, 1800))");
    }

    #[test]
    fn the_cubic_basis_is_removed_and_poly3_read_back() {
        // What `bayes` stores when it chooses the cubic.
        let bayes = FeatureSpec {
            signals: vec![
                "T = mean(t_a, t_b)".into(),
                "Tclamped = clamp(T, -3.0e1, 5.0e1)".into(),
            ],
            features: vec![
                "T".into(),
                "rate(T)".into(),
                "sq(Tclamped)".into(),
                "Tclamped * sq(Tclamped)".into(),
            ],
        };
        let u = user_spec(&bayes);
        assert_eq!(u.signals, vec!["T = mean(t_a, t_b)".to_string()]);
        assert_eq!(u.features, vec!["T".to_string(), "rate(T)".to_string()]);
        // What `poly3` stores.
        let poly3 = FeatureSpec {
            signals: vec!["Tclamped = clamp(mean(t_a, t_b), -3e1, 5e1)".into()],
            features: vec![
                "Tclamped".into(),
                "sq(Tclamped)".into(),
                "Tclamped * sq(Tclamped)".into(),
            ],
        };
        let u = user_spec(&poly3);
        assert!(u.signals.is_empty());
        assert_eq!(u.features, vec!["mean(t_a, t_b)".to_string()]);
        assert_eq!(user_spec(&u), u);
    }
}
