//! The report: one self-contained HTML file (no network, no scripts from elsewhere) with inline SVG
//! plots — measured error and model over time with temperature on a second axis, residual against
//! temperature with heating and cooling told apart, residual against the top candidates, residual
//! per segment for each model (before/after bars), and the verdict and figures as text.
//!
//! The plots show the run the models were run over ([`ReportInput::models`]): the caller passes the
//! held-out run there when it has one, since that is where a base model fails and where the
//! diagnosis looks; [`View`] names that run, its channel and its data, so the candidate plots are
//! drawn on it too. Every number goes through [`crate::render::num`] (plain notation, unit
//! appended; a change is negative when the residual fell).
//!
//! Layout: this module writes the page and its tables, [`figures`] the plots, [`plot`] the plot
//! areas (plotters' SVG backend), [`bars`] the segment chart. A short inline script only checks that every plot has laid out
//! (non-empty bounding box) and holds data, and records the counts on `<body data-plots=…
//! data-plots-ok=…>`, which the headless-Chromium test (`host-tools/tests/report_chromium.rs`)
//! reads back.

mod bars;
pub mod calibrate;
mod figures;
pub mod fleet;
mod plot;
mod tables;

use crate::render::num;
use plot::esc;
use std::fmt::Write as _;
use tcomp_discover::Analysis;
use tcomp_discover::segments;
use tcomp_train::Dataset;
use tcomp_train::metrics::Run;

/// One model's run over the report's data.
#[derive(Clone, Debug)]
pub struct ModelRun {
    /// Legend name.
    pub name: String,
    /// The run.
    pub run: Run,
}

/// What the report shows.
pub struct ReportInput<'a> {
    /// Title.
    pub title: String,
    /// Name of the data file.
    pub data_name: String,
    /// Output unit (empty: the one the channel's column name carries).
    pub unit: String,
    /// Models (the first defines the segments), each run over the run the report shows.
    pub models: Vec<ModelRun>,
    /// A diagnosis of the first model, when available.
    pub analysis: Option<&'a Analysis>,
    /// Known noise floor (100 s bins), when available.
    pub noise_floor: Option<f64>,
}

/// What the report knows about the run it shows, beyond [`ReportInput`]; every field may be left
/// at its default (`View::default()`), and the report then says less.
#[derive(Clone, Debug, Default)]
pub struct View<'a> {
    /// The channel: the target column (default: the diagnosis' target).
    pub channel: Option<String>,
    /// The temperature column (its name gives the temperature unit; default °C).
    pub temperature: Option<String>,
    /// The data the models were run over (the candidate plots compute candidates on it).
    pub data: Option<&'a Dataset>,
    /// Its time column.
    pub time: Option<String>,
    /// Gap threshold (s) at which feature state is reset, as in the models' runs.
    pub gap_s: Option<f64>,
    /// What the run is, e.g. "held-out run verify.csv".
    pub run: Option<String>,
}

impl View<'_> {
    /// The channel's name: the view's, else the diagnosis' target, else "run".
    fn subject(&self, input: &ReportInput<'_>) -> String {
        self.channel
            .clone()
            .or_else(|| input.analysis.map(|a| a.diagnosis.model.target.clone()))
            .filter(|c| !c.is_empty())
            .unwrap_or_else(|| "run".into())
    }

    /// The output unit: the input's, else the one the channel's column name carries.
    fn unit(&self, input: &ReportInput<'_>) -> String {
        num::unit_or_column(&input.unit, &self.subject(input))
    }

    /// The temperature unit, from the temperature column's name (°C when it carries none).
    fn temperature_unit(&self) -> String {
        self.temperature
            .as_deref()
            .and_then(num::unit_of_column)
            .unwrap_or("°C")
            .to_string()
    }

    /// What the shown run is.
    fn run_label(&self) -> String {
        self.run.clone().unwrap_or_else(|| "the run shown".into())
    }
}

/// Renders the report: the page, its tables, and the plots of [`figures`].
#[allow(dead_code, reason = "the entry point of callers without a view")]
pub fn render(input: &ReportInput<'_>) -> String {
    render_with(input, &View::default())
}

/// [`render`] with what `view` says about the run shown (its channel, units and data).
pub fn render_with(input: &ReportInput<'_>, view: &View<'_>) -> String {
    let mut h = String::new();
    head(&mut h, &input.title);
    let _ = writeln!(h, "<h1>{}</h1>", esc(&input.title));
    body(&mut h, input, view);
    tail(&mut h);
    h
}

/// The page's head (title, style) and the opening of its body.
fn head(h: &mut String, title: &str) {
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>body{{font-family:sans-serif;max-width:900px;margin:1em auto;color:#222}}.scroll{{overflow-x:auto;margin:8px 0 18px}}table{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right;white-space:nowrap}}td:first-child,th:first-child{{text-align:left}}.verdict{{font-size:16px;padding:8px;background:#f4f4e8;border-left:4px solid #c90}}.flag{{font-size:15px;padding:8px;background:#fbe9e7;border-left:4px solid #c62828;color:#b71c1c;font-weight:bold}}.row{{display:flex;gap:0}}svg{{display:block;margin:10px 0}}</style></head>\n<body>\n",
        t = esc(title),
    );
}

/// One run's section: the channel line, the verdict, the figures, the plots and the segments.
fn body(h: &mut String, input: &ReportInput<'_>, view: &View<'_>) {
    let unit = view.unit(input);
    let subject = view.subject(input);
    let _ = writeln!(
        h,
        "<p>Channel: <b>{c}</b>{u}. Data: {d}{r}</p>",
        c = esc(&subject),
        u = if unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", esc(&unit))
        },
        d = esc(&input.data_name),
        r = view
            .run
            .as_deref()
            .map(|r| format!("; plots on the {}", esc(r)))
            .unwrap_or_default(),
    );
    let segs = input
        .models
        .first()
        .map(|m| segments::table(&m.run))
        .unwrap_or_default();
    if let Some(a) = input.analysis {
        tables::verdict(h, a, &unit, input.noise_floor);
    }
    tables::figures(h, input, &unit);
    h.push_str("<h2>Plots</h2>\n");
    if let Some(s) = figures::time_plot_in(input, view) {
        h.push_str(&s);
    }
    h.push_str("<div class=\"row\">\n");
    for s in figures::temp_plots_in(input, view) {
        h.push_str(&s);
    }
    h.push_str("</div>\n");
    if let Some(a) = input.analysis {
        for s in figures::candidate_plots_in(a, input, view) {
            h.push_str(&s);
        }
        for s in figures::profile_plots(a) {
            h.push_str(&s);
        }
        for s in figures::placebo_plots(a) {
            h.push_str(&s);
        }
    }
    if let Some(s) = figures::segment_bars_in(input, &segs, view) {
        h.push_str(&s);
    }
    tables::segments(h, input, &segs, &unit, &view.temperature_unit());
}

/// The inline check of the plots (see the module doc) and the end of the page.
fn tail(h: &mut String) {
    h.push_str("<script>(function(){var s=document.querySelectorAll('svg.plot'),ok=0;for(var i=0;i<s.length;i++){var b=s[i].getBBox();if(b.width>0&&b.height>0&&Number(s[i].getAttribute('data-points'))>0)ok++;}document.body.setAttribute('data-plots',String(s.length));document.body.setAttribute('data-plots-ok',String(ok));})();</script>\n</body></html>\n");
}
