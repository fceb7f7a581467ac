//! The built-in demo: an IFOG whose bias holds a Shupe-type T·dT/dt term, fitted first with the
//! traditional (T, dT/dt) model; the diagnosis finds the missing term, one more feature fixes it,
//! and the error falls on a verification profile the fit never saw.
//!
//! Why in the tool: the README's main command must work with no user data, and it is a user of the
//! analysis, not part of it, so `tcomp-discover` carries neither the narrative nor the simulator.
//! The scenario and the simulate → fit → evaluate steps come from `tcomp-demo`, which the
//! discovery tests run too, so the narrative cannot drift from what is tested; the candidate table
//! and the report come from [`crate::render`], as for `diagnose` and `report`.
//!
//! [`steps`] holds the six paragraphs of the narrative, [`files`] what the demo writes.

mod files;
mod steps;

use std::path::PathBuf;
use tcomp_demo::Simulated;
use tcomp_discover::Verdict;
use tcomp_train::EvalReport;

/// Options of the demo.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Seed of the simulation.
    pub seed: u64,
    /// Output step of the simulated runs (s); 1 s in `tcomp demo` by default, larger for quick
    /// checks.
    pub step_s: f64,
}

/// The narrative as it is told: each paragraph goes to the caller as it happens.
struct Story<F: FnMut(&str)> {
    say: F,
}

impl<F: FnMut(&str)> Story<F> {
    fn tell(&mut self, paragraph: &str) {
        (self.say)(paragraph);
    }
}

/// The simulated runs and what the demo knows about them.
struct Scene {
    sim: Simulated,
    /// Noise floor of the verification run (100 s bins).
    floor: f64,
    /// Output unit.
    unit: String,
}

/// What the demo found, for `tcomp demo --json`.
pub struct Summary {
    /// The simulated sensor's output column.
    pub target: String,
    /// Its unit.
    pub unit: String,
    /// Noise floor of the verification run (100 s bins).
    pub noise_floor: f64,
    /// The traditional model on the verification run.
    pub before: EvalReport,
    /// The model with the effect the diagnosis named, on the verification run.
    pub after: Option<EvalReport>,
    /// The diagnosis of the traditional model.
    pub verdict: Verdict,
    /// The verdict in one sentence.
    pub verdict_text: String,
    /// The features added.
    pub added: Vec<String>,
}

/// Runs the demo, writing data, blobs and the report into `opts.out`; `say` receives each
/// paragraph of the narrative as it happens.
pub fn run(opts: &DemoOptions, say: impl FnMut(&str)) -> anyhow::Result<Summary> {
    let mut story = Story { say };
    files::create_dir(&opts.out)?;
    let scene = steps::simulate(opts, &mut story)?;
    let before = steps::fit_before(opts, &scene, &mut story)?;
    let analysis = steps::diagnose(&scene, &before, &mut story)?;
    let after = steps::add_effect(opts, &scene, &before, &analysis, &mut story)?;
    steps::report(opts, &scene, &analysis, after.as_ref(), &mut story)?;
    let d = &analysis.diagnosis;
    Ok(Summary {
        target: scene.sim.verify_truth.columns.target.clone(),
        unit: scene.unit.clone(),
        noise_floor: scene.floor,
        before: before.eval,
        after: after.as_ref().map(|a| a.eval.clone()),
        verdict: d.verdict,
        verdict_text: d.verdict_text.clone(),
        added: after.map(|a| a.added).unwrap_or_default(),
    })
}
