//! The registry of fit methods: the list of methods, each with its own options, and the lookup by
//! name. The one place a new method goes besides its own module: one line of [`registry!`].
//!
//! Why apart from the trait ([`crate::method`]): the registry imports every method and every
//! method imports the trait, so the trait's module must not be the registry's (that made an
//! import circle through every method). A method's options are the fields of its struct (e.g.
//! [`crate::bayes::Bayes`]: `linear`, `cubic`, `additive`), a layer deriving `serde::Deserialize`
//! and, with the `cli` feature, `clap::Args`; [`MethodSettings`] lays every method's struct into
//! the method options ([`crate::spec::MethodOptions`]), so the TOML keys and the flags of each
//! method are its own fields, and [`Method::fitter`] hands the selected method its options.

use crate::error::TrainError;
use crate::method::FitMethod;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Defines [`Method`] (the registry's key), [`MethodSettings`] (every method's options) and
/// [`Method::fitter`] from one line per method, `Variant => field: Type` (the field of
/// [`MethodSettings`] holding the method's struct, which implements
/// [`FitMethod`]), the default method first.
macro_rules! registry {
    ($( $(#[$doc:meta])* $variant:ident => $field:ident : $ty:path, )+) => {
        /// A training method: the registry's key (a plain `Copy` value for options and the
        /// summary); [`Method::fitter`] is the implementation, with its options.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
        #[serde(rename_all = "lowercase")]
        pub enum Method {
            $( $(#[$doc])* $variant, )+
        }

        crate::layer! {
            /// Every method's own options, each method's struct flattened (its fields are keys of
            /// the fit spec and, with `cli`, flags), all unset by default.
            #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
            #[cfg_attr(feature = "cli", derive(clap::Args))]
            pub struct MethodSettings {
                $(
                    #[doc = concat!("The options of `", stringify!($field), "`.")]
                    #[serde(flatten)]
                    #[cfg_attr(feature = "cli", command(flatten))]
                    pub $field: $ty,
                )+
            }
        }

        impl Method {
            /// Every method, the default first.
            pub const ALL: [Method; [$(Method::$variant),+].len()] = [$(Method::$variant),+];

            /// The implementation, with its options from `settings`: the registry's one `match`.
            pub fn fitter(self, settings: &MethodSettings) -> &dyn FitMethod {
                match self {
                    $( Method::$variant => &settings.$field, )+
                }
            }
        }

        impl MethodSettings {
            /// Checks every method's own options (a spec may set those of a method it does not
            /// select; they are refused all the same, before any data are read).
            pub fn check(&self) -> Result<(), TrainError> {
                $( FitMethod::check_settings(&self.$field)?; )+
                Ok(())
            }
        }
    };
}

registry! {
    /// Bayesian-regularised RBF with evidence-chosen structure.
    Bayes => bayes: crate::bayes::Bayes,
    /// k-means + width heuristic + least squares.
    Mse => mse: crate::mse::Mse,
    /// Gradient descent on weights, centers and widths.
    Gradient => gradient: crate::gradient::Gradient,
    /// Cubic in one clamped temperature.
    Poly3 => poly3: crate::poly3::Poly3,
}

impl Method {
    /// The method's name, as `--method` takes it.
    pub fn name(self) -> &'static str {
        self.fitter(&MethodSettings::default()).name()
    }

    /// The known names, comma-separated.
    pub fn names() -> String {
        Self::ALL.map(Method::name).join(", ")
    }

    /// `--method`'s help, from the registry: each name with its line, the default first.
    pub fn help() -> String {
        let list: Vec<String> = Self::ALL
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let default = if i == 0 { " (default)" } else { "" };
                let about = m.fitter(&MethodSettings::default()).about();
                format!("  {}{default}: {about}", m.name())
            })
            .collect();
        format!("Method:\n{}", list.join("\n"))
    }
}

impl Default for Method {
    fn default() -> Self {
        Method::ALL[0]
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = TrainError;
    fn from_str(s: &str) -> Result<Self, TrainError> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| TrainError::Unknown {
                what: "method",
                name: s.into(),
                known: Self::names(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::budget::{self, DEFAULT_BUDGET_BYTES, Shape};
    use crate::method::CenterSelection;

    #[test]
    fn every_method_parses_back_from_its_name_and_is_in_the_help() {
        let help = Method::help();
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>().ok(), Some(m));
            assert!(help.contains(m.name()), "{help}");
        }
        assert!(help.starts_with("Method:\n  bayes (default): "), "{help}");
        let e = "magic".parse::<Method>().err().map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some("unknown method `magic` (known: bayes, mse, gradient, poly3)")
        );
    }

    // The memory estimate of each method (moved here from `budget`, which knows no method).
    fn estimate(method: Method, select: CenterSelection, samples: usize) -> u64 {
        let shape = Shape {
            rows: 2_160_000,
            samples,
            features: 2,
            centers: None,
            threads: 4,
        };
        let mut settings = MethodSettings::default();
        settings.mse.select = Some(format!("{select:?}").to_lowercase());
        budget::estimate(&shape, method.fitter(&settings).memory(&shape))
    }

    #[test]
    fn unaveraged_ols_of_a_100_hz_run_is_over_the_budget_and_averaged_is_not() {
        let big = estimate(Method::Mse, CenterSelection::Ols, 2_160_000);
        // The reviewer measured 7.5 GB for this fit.
        assert!((6.5e9..9e9).contains(&(big as f64)), "{big}");
        let binned = estimate(Method::Mse, CenterSelection::Ols, 21_600);
        assert!(binned < DEFAULT_BUDGET_BYTES, "{binned}");
    }

    #[test]
    fn estimate_grows_linearly_with_samples() {
        let a = estimate(Method::Bayes, CenterSelection::Kmeans, 100_000) as f64;
        let b = estimate(Method::Bayes, CenterSelection::Kmeans, 200_000) as f64;
        let c = estimate(Method::Bayes, CenterSelection::Kmeans, 400_000) as f64;
        // Linear: equal steps for equal increments (no rows² term).
        assert!(((c - b) / (b - a) - 2.0).abs() < 1e-6, "{a} {b} {c}");
    }
}
