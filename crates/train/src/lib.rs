//! Host-side training of temperature-compensation models for inertial sensors.
//!
//! The pipeline: [`dataset`] loads a measurement CSV with precise errors; [`features`] runs the
//! core's feature program over it (the code the firmware runs) and [`binning`] averages the rows
//! into time bins; a method fits an RBF in f64 —
//! [`bayes`] (default, MacKay evidence), [`mse`] (centers by k-means or orthogonal least squares), [`gradient`] or
//! the [`poly3`] baseline, each an implementation of [`method::FitMethod`] listed in [`registry`]; [`blob_io`]
//! stores it as the core's blob; [`metrics`] measures it by running the decoded blob through the
//! core's f32 `Channel`. [`train::fit`] ties it together for `tcomp fit`; [`spec`] reads the TOML spec.
//!
//! # Features
//!
//! - `cli` (off by default): the command-line derives — `clap::Args` on the option structs of
//!   [`spec`], `clap::ValueEnum` on the load policies of [`dataset`] — and the bounds' clap value
//!   parsers ([`options`]). Why behind a feature: this is a library of training that other programs
//!   (the discovery, a user's own tool) link without a command-line parser; only the programs that
//!   flatten these structs into their flags (`tcomp`) enable it. The structs, their TOML keys and
//!   the bounds' checks are the same with or without it.
//!
//! ```no_run
//! use tcomp_train::{Dataset, FitOptions, fit};
//! let data = Dataset::load(std::path::Path::new("run.csv")).unwrap();
//! let mut opts = FitOptions::new("gyro_dph", &["T", "rate(T)"]);
//! opts.spec.signals.push("T = mean(t_anode_c, t_shell_c)".into());
//! opts.reference = Some("ref_dph".into());
//! let fitted = fit(&data, &opts).unwrap();
//! println!("{}", fitted.summary.train.residual_std);
//! ```

pub mod ar1;
pub mod autopilot;
pub mod bayes;
pub mod binning;
pub mod blob_io;
mod budget;
mod cubic;
pub mod dataset;
mod error;
pub mod evidence;
pub mod features;
mod fit_options;
pub mod gradient;
mod kmeans;
pub mod layer;
pub mod long_log;
pub mod method;
pub mod metrics;
pub mod mse;
pub mod num;
mod ols;
pub mod options;
mod pin;
pub mod poly3;
pub mod progress;
pub mod rbf64;
pub mod registry;
mod rows;
pub mod spec;
pub mod train;
pub mod units;

pub use dataset::{DataError, Dataset};
pub use error::TrainError;
pub use long_log::{StreamOptions, eval_stream, eval_stream_reader};
pub use metrics::{EvalReport, Roles};
pub use spec::{ChannelOptions, FeatureOptions, MethodOptions, RunOptions, Spec};
pub use train::{
    FitOptions, FitSummary, Fitted, Method, MethodSettings, evaluate, fit, fit_unmeasured,
    fit_with_progress,
};
