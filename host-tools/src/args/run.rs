//! `RunArgs`: the run a command reads — `--data`, and the trainer's [`RunOptions`] (`--reference`,
//! `--reference-value`, `--from/--until`, `--gap`, `--power-on`) — flattened into `fit`, `eval`, `diagnose`,
//! `compare` and `report`.
//!
//! Why one struct: these flags were declared once per command, with drifting help texts, bounds
//! and window semantics. Here they are declared once (the numbers through the trainer's table of
//! bounds), and the window means the same everywhere: rows with `from ≤ time < until` of the
//! model's time column, refused when `--from` is not before `--until` or fewer than two rows
//! remain. The bin (`--bin`) and the segment temperature stay with each command: their defaults
//! differ by command.

use std::path::PathBuf;
use tcomp_train::{Dataset, Roles, RunOptions};

/// The host's model type.
type HostModel<'a> = tcomp_core::Model<
    'a,
    { tcomp_train::rbf64::C },
    { tcomp_train::features::F },
    { tcomp_train::features::N },
>;

/// The run a command reads.
#[derive(clap::Args, Clone, Debug)]
pub struct RunArgs {
    /// Measurement CSV (or .csv.gz).
    #[arg(long)]
    pub data: PathBuf,
    /// Reference, window and gaps.
    #[command(flatten)]
    pub run: RunOptions,
}

impl RunArgs {
    /// Refuses a window whose start is not before its end, before any file is read.
    pub fn check_window(&self) -> anyhow::Result<()> {
        if let (Some(from), Some(until)) = (self.run.from, self.run.until) {
            anyhow::ensure!(
                from < until,
                "--from {from} must be less than --until {until} (rows with from ≤ time < until \
                 are used)"
            );
        }
        Ok(())
    }

    /// Whether the reference is overridden.
    pub fn overrides_reference(&self) -> bool {
        self.run.reference.is_some() || self.run.reference_value.is_some()
    }

    /// The model's column roles with this run's reference override (a constant wins over a
    /// column, as in `fit`).
    pub fn roles(&self, model: &HostModel<'_>) -> Roles {
        let mut roles = Roles::of_model(model);
        roles.power_on_s = self.run.power_on;
        if let Some(r) = &self.run.reference {
            roles.reference = Some(r.clone());
        }
        if let Some(v) = self.run.reference_value {
            roles.reference = None;
            roles.reference_value = Some(v);
        }
        roles
    }

    /// The window `model` was trained on, when `--data` is its training file and no
    /// `--from/--until` was given: the rows to diagnose, and the rest of the file as the run held
    /// out (what `tcomp fit --from/--until` left out of training).
    pub fn model_window(&self, model: &HostModel<'_>) -> Option<[f64; 2]> {
        if self.run.from.is_some() || self.run.until.is_some() {
            return None;
        }
        let t = tcomp_train::blob_io::TrainedOn::parse(model.meta.trained_on);
        let same =
            |a: &std::path::Path, b: &std::path::Path| match (a.canonicalize(), b.canonicalize()) {
                (Ok(a), Ok(b)) => a == b,
                _ => a == b,
            };
        t.window
            .filter(|_| same(std::path::Path::new(&t.file), &self.data))
    }

    /// Loads `--data` for `model` ([`Self::load_options`]), says what the loading policies did
    /// (on stderr, unless `quiet`) and keeps the rows of the window; at least two rows must
    /// remain, since one row has no spread and every figure would be a meaningless zero.
    pub fn load(&self, model: &HostModel<'_>, quiet: bool) -> anyhow::Result<Dataset> {
        self.check_window()?;
        let opts = self.load_options(model);
        let time = opts.time().to_string();
        let time = time.as_str();
        let mut data = Dataset::load_with(&self.data, &opts, &tcomp_train::progress::Silent)?;
        if !quiet {
            for n in data.notes() {
                eprintln!("note: {n}");
            }
        }
        let windowed = self.run.from.is_some() || self.run.until.is_some();
        if windowed {
            data = data.select_time(
                time,
                self.run.from.unwrap_or(f64::NEG_INFINITY),
                self.run.until.unwrap_or(f64::INFINITY),
            )?;
        }
        if data.len() < 2 {
            let which = if windowed {
                "--from/--until select"
            } else {
                "the file has"
            };
            anyhow::bail!(
                "{}: {which} {} row(s), and at least 2 are needed to measure anything",
                self.data.display(),
                data.len()
            );
        }
        Ok(data)
    }

    /// Loads another run of `model` (`--verify`) with this run's policies, saying what they did
    /// unless `quiet`.
    pub fn load_other(
        &self,
        path: &std::path::Path,
        model: &HostModel<'_>,
        quiet: bool,
    ) -> anyhow::Result<Dataset> {
        let data = Dataset::load_with(
            path,
            &self.load_options(model),
            &tcomp_train::progress::Silent,
        )?;
        if !quiet {
            for n in data.notes() {
                eprintln!("note: {n}");
            }
        }
        Ok(data)
    }

    /// The options of a streamed evaluation of `--data` ([`tcomp_train::eval_stream`]) with
    /// these roles, bins of `bin_s` seconds and the segment temperature column.
    pub fn stream(
        &self,
        roles: Roles,
        bin_s: f64,
        temperature: Option<String>,
    ) -> tcomp_train::StreamOptions {
        tcomp_train::StreamOptions {
            roles,
            bin_s,
            temperature,
            gap_s: self.run.gap,
            from: self.run.from,
            until: self.run.until,
            repeated_time: self.run.repeated_time.unwrap_or_default(),
            missing: self.run.missing.unwrap_or_default(),
        }
    }

    /// How `model`'s run is loaded: its time column, the columns it uses (target first) and this
    /// run's policies for messy rows.
    pub fn load_options(&self, model: &HostModel<'_>) -> tcomp_train::dataset::LoadOptions {
        let roles = self.roles(model);
        let mut columns = vec![roles.target.clone()];
        columns.extend(roles.reference.clone());
        columns.extend(model.program.inputs.iter().map(|s| s.to_string()));
        self.run.load_options(&roles.time, columns)
    }
}
