//! The fleet page of `tcomp calibrate --units`: the rule that names outliers (stated first), the
//! units it named, then per channel the spread of each statistic over the units and a plot of the
//! held-out residual of every unit, outliers in red.

use super::plot::{Plot, range};
use super::{esc, head, tail};
use crate::calibrate::fleet::Fleet;
use crate::calibrate::spec::CalSpec;
use crate::render::num;
use std::fmt::Write as _;

/// The residual of every unit of channel `ci`, by unit number.
fn residual_plot(f: &Fleet, ci: usize, name: &str, unit: &str) -> String {
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    let mut colors = Vec::new();
    for (i, r) in f.rows.iter().enumerate() {
        if let Some(v) = r.channels.get(ci).and_then(|c| c.residual_rms) {
            xs.push(i as f64 + 1.0);
            ys.push(v);
            let out = f
                .outliers
                .iter()
                .any(|o| o.unit == r.unit && o.channel == name);
            colors.push(if out { "#c62828" } else { "#1565c0" });
        }
    }
    let (lo, hi) = range(&ys);
    let mut p = Plot::new(
        &format!("{name}: held-out residual RMS per unit"),
        "unit (in folder order)",
        &if unit.is_empty() {
            "held-out residual RMS".to_string()
        } else {
            format!("held-out residual RMS ({unit})")
        },
        (0.0, xs.len() as f64 + 1.0),
        (lo, hi),
    );
    p.dots(&xs, &ys, &colors);
    p.finish()
}

/// The whole page.
pub fn page(f: &Fleet, spec: &CalSpec) -> String {
    let title = format!("tcomp calibrate: fleet of {} units", f.units);
    let mut h = String::new();
    head(&mut h, &title);
    let _ = writeln!(
        h,
        "<h1>{}</h1>\n<p>Spec: {}. Outlier rule: {} — median and MAD, so the outliers do not widen the yardstick they are measured with; 5 rather than 3.5 because a line of a thousand units makes thousands of comparisons (|z| &gt; 5 happens 5.7·10⁻⁷ of the time for a normal spread).</p>",
        esc(&title),
        esc(&spec.path.display().to_string()),
        esc(&f.rule)
    );
    if f.outliers.is_empty() {
        h.push_str("<p>No unit stands apart.</p>\n");
    } else {
        let _ = writeln!(
            h,
            "<div class=\"flag\">Outlier units: {}</div>",
            esc(&f.outlier_units.join(", "))
        );
        h.push_str("<div class=\"scroll\"><table><tr><th>unit</th><th>channel</th><th>statistic</th><th>value</th><th>robust z</th></tr>\n");
        for o in &f.outliers {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&o.unit),
                esc(&o.channel),
                esc(&o.statistic),
                num::plain(o.value, 4),
                num::signed(o.z, 1)
            );
        }
        h.push_str("</table></div>\n");
    }
    for (ci, c) in f.channels.iter().enumerate() {
        let (name, spreads) = (&c.name, &c.spreads);
        let _ = writeln!(h, "<h2>{}</h2>", esc(name));
        h.push_str("<div class=\"scroll\"><table><tr><th>statistic</th><th>median</th><th>robust σ (1.4826·MAD)</th><th>min</th><th>max</th><th>units</th></tr>\n");
        for s in spreads {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&s.statistic),
                num::plain(s.median, 4),
                num::plain(s.robust_sigma, 4),
                num::plain(s.min, 4),
                num::plain(s.max, 4),
                s.units
            );
        }
        h.push_str("</table></div>\n");
        h.push_str(&residual_plot(f, ci, name, &c.unit));
    }
    tail(&mut h);
    h
}
