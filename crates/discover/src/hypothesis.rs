//! What a hypothesis is: one candidate (the features it adds, or puts in place of some of the
//! model's, and its physical name) and how it was read off the data. Plain types, below both the
//! templates that build candidates ([`crate::families`]) and the generator that lists them
//! ([`crate::candidates`]), which re-exports them.

use serde::Serialize;
use tcomp_core::expr::Expr;

/// The kind of physical effect a candidate stands for: the core's vocabulary, shared with the
/// simulator (which hides effects of these kinds).
pub use tcomp_core::EffectKind;

/// One candidate: the features to add, or to put in place of some of the model's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Candidate {
    /// Effect kind.
    pub kind: EffectKind,
    /// Physical name, e.g. "Shupe-type T·dT/dt of t_coil_c".
    pub effect: String,
    /// Feature expressions to add (one, or two/three for gradient sets), or to put in place of
    /// `replaces`.
    pub expressions: Vec<String>,
    /// The searched parameter: τ (s) for lags and warm-up, threshold for hysteresis, window (s)
    /// for rates.
    pub parameter: Option<f64>,
    /// The model's features the expressions replace, in order (empty: they are added).
    pub replaces: Vec<String>,
    /// Set when the candidate only re-states a feature the model already has (its rate with
    /// another window): a refinement of that feature, not a missing effect.
    pub refines: Option<String>,
}

impl Candidate {
    /// A candidate added beside the model's features.
    pub fn added(kind: EffectKind, effect: String, expressions: Vec<String>, p: f64) -> Self {
        Candidate {
            kind,
            effect,
            expressions,
            parameter: Some(p),
            replaces: Vec::new(),
            refines: None,
        }
    }

    /// The feature list `features` with this candidate applied: each replaced feature swapped for
    /// its new expression in place, the others appended.
    pub fn applied_to(&self, features: &[String]) -> Vec<String> {
        let mut out: Vec<String> = features.to_vec();
        let mut extra = Vec::new();
        for (k, e) in self.expressions.iter().enumerate() {
            match self
                .replaces
                .get(k)
                .and_then(|r| out.iter().position(|f| f == r))
            {
                Some(i) => {
                    if let Some(slot) = out.get_mut(i) {
                        slot.clone_from(e);
                    }
                }
                None => extra.push(e.clone()),
            }
        }
        out.extend(extra);
        out
    }
}

/// How a candidate was read off the data, when not by a template's parameter.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Searched {
    /// Not read off the data: a plain candidate, or a template's family
    /// ([`crate::families::Family::search`]).
    #[default]
    No,
    /// Read off a bank of columns by automatic relevance determination ([`crate::dynamics`]).
    Bank(Vec<String>),
    /// The best of these alternatives, each a whole candidate: a composition's members across its
    /// parameters ([`crate::compose`]), chosen among `among` shapes searched.
    Alternatives {
        /// The members, each one expression.
        members: Vec<String>,
        /// Shapes the composition was chosen among.
        among: usize,
    },
}

impl Searched {
    /// Whether the candidate was read off the data this way.
    pub fn is_read(&self) -> bool {
        !matches!(self, Searched::No)
    }
}

/// A number as the expressions print it, without a trailing `.0`.
pub(crate) fn num(v: f64) -> String {
    Expr::num(v).to_string()
}
