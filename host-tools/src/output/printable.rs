//! Strings from a file, made safe to print on a terminal.
//!
//! Why: a blob's strings (column names, axis, unit, expressions, the training file's name) come from
//! whoever wrote the blob. Printed raw, an escape sequence in them can retitle the terminal, hide
//! text or reorder it (bidirectional overrides). So `inspect` (and `eval`, `diagnose`, which print a
//! few of them) escapes control and invisible characters in its text, and in `--json` writes them
//! as `\uXXXX` escapes, which JSON readers turn back into the same string (serde_json escapes only
//! U+0000–U+001F by itself, not DEL, the C1 controls such as the one-byte CSI U+009B, or the
//! bidirectional overrides).

use std::fmt::Write as _;

/// Characters never printed raw: controls (C0, DEL, C1) and the invisible formatting characters
/// that change how the surrounding text is shown (soft hyphen, zero-width and bidirectional marks,
/// embeddings, overrides and isolates, the byte-order mark, interlinear annotation).
pub fn is_unsafe(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{ad}'
                | '\u{61c}'
                | '\u{180e}'
                | '\u{200b}'..='\u{200f}'
                | '\u{2028}'..='\u{202e}'
                | '\u{2060}'..='\u{206f}'
                | '\u{feff}'
                | '\u{fff9}'..='\u{fffb}'
        )
}

/// `s` for a terminal: unsafe characters as Rust-style escapes (`\n`, `\u{1b}`) and the backslash
/// doubled so an escape cannot be forged; everything else (°, µ, Δ) unchanged.
pub fn text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if is_unsafe(c) => {
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out
}

/// A whole printed report whose lines hold strings from a blob: unsafe characters escaped as in
/// [`text`], newlines kept (the report's own layout), backslashes left alone.
pub fn lines(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c != '\n' && is_unsafe(c) {
            let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
        } else {
            out.push(c);
        }
    }
    out
}

/// Serialised JSON with every unsafe character written as a `\uXXXX` escape (UTF-16 pairs above
/// U+FFFF). serde_json already escapes U+0000–U+001F inside strings, so a raw one is layout
/// (newline, indent) and stays; outside strings JSON text is ASCII, so this only touches string
/// contents, and the parsed value is unchanged.
pub fn json(serialised: &str) -> String {
    let mut out = String::with_capacity(serialised.len());
    for c in serialised.chars() {
        if c >= ' ' && is_unsafe(c) {
            let mut units = [0u16; 2];
            for u in c.encode_utf16(&mut units) {
                let _ = write!(out, "\\u{u:04x}");
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn escapes_controls_and_overrides_but_keeps_units() {
        let s = "a\u{1b}]0;x\u{7}b\u{9b}c\u{202e}d\\e °C µg";
        let t = text(s);
        assert_eq!(t, "a\\u{1b}]0;x\\u{7}b\\u{9b}c\\u{202e}d\\\\e °C µg");
        assert!(!t.chars().any(is_unsafe));
    }

    #[test]
    fn lines_keep_the_layout() {
        assert_eq!(lines("a\tb\n°C\u{1b}[0m\\\n"), "a\\u{9}b\n°C\\u{1b}[0m\\\n");
    }

    #[test]
    fn json_stays_the_same_value() {
        let v = serde_json::json!({"unit": "x\u{1b}[2J\u{7f}\u{9b}\u{202e}°\u{feff}"});
        let raw = serde_json::to_string(&v).unwrap();
        let safe = json(&raw);
        assert!(!safe.chars().any(is_unsafe), "{safe}");
        let back: serde_json::Value = serde_json::from_str(&safe).unwrap();
        assert_eq!(back, v);
        let pretty = json(&serde_json::to_string_pretty(&v).unwrap());
        assert!(
            !pretty.chars().any(|c| c != '\n' && is_unsafe(c)),
            "{pretty}"
        );
        let back: serde_json::Value = serde_json::from_str(&pretty).unwrap();
        assert_eq!(back, v);
    }
}
