//! Binned columns of expressions already computed on one run, kept by expression.
//!
//! Why: a diagnosis scores the same expressions many times — the search over candidates, each
//! candidate's placebos, the surrogate fits of the confirmation, the dynamics' lag banks — and
//! running a feature program over every row of the run is most of what each score costs.
//!
//! On a run without gaps the value of a feature depends on its own expression and the run alone,
//! not on the features a program computes beside it, so a column kept from an earlier call is
//! the column a new call would compute. Across a gap it does not: the program restarts its
//! filters or carries them over by its longest time constant ([`tcomp_core::stream::gap_resets`]),
//! a property of the whole program, so `rate(T)` beside `lag(T, 3000)` is not `rate(T)` alone.
//! So columns are kept only for a run without gaps ([`ColumnCache::for_run`]), and only there are
//! several computed by one program ([`ColumnCache::keeps`]): the model's signals and the reading of
//! the inputs, which every program repeats, are then paid once for up to eight columns.

use crate::error::Result;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

/// The columns of one run, by expression (see the module doc); `None`: a run with gaps, whose
/// columns are computed as asked, each call on its own.
pub(crate) struct ColumnCache(Option<Mutex<HashMap<String, Arc<Vec<f64>>>>>);

impl ColumnCache {
    /// The cache of a run whose stretches after gaps begin at `starts` (see the module doc): it
    /// keeps columns only when there is no gap.
    pub(crate) fn for_run(starts: &[usize]) -> Self {
        Self(starts.iter().all(|&s| s == 0).then(Mutex::default))
    }

    /// Whether columns are kept (a run without gaps): a column is then the same whatever it is
    /// computed beside, so the missing ones may be computed together.
    pub(crate) fn keeps(&self) -> bool {
        self.0.is_some()
    }

    /// The columns of `exprs` in order: those kept, and the rest from `compute` (called once,
    /// with the missing expressions, each once, in their first order), which are then kept. An
    /// error of `compute` is returned as it is, and nothing of that call is kept.
    pub(crate) fn columns(
        &self,
        exprs: &[String],
        compute: impl FnOnce(&[String]) -> Result<Vec<Vec<f64>>>,
    ) -> Result<Vec<Vec<f64>>> {
        let Some(cache) = &self.0 else {
            return compute(exprs);
        };
        let missing: Vec<String> = {
            let kept = cache.lock().unwrap_or_else(PoisonError::into_inner);
            let mut m: Vec<String> = Vec::new();
            for e in exprs {
                if !kept.contains_key(e) && !m.contains(e) {
                    m.push(e.clone());
                }
            }
            m
        };
        let fresh = if missing.is_empty() {
            Vec::new()
        } else {
            compute(&missing)?
        };
        let mut kept = cache.lock().unwrap_or_else(PoisonError::into_inner);
        for (e, c) in missing.into_iter().zip(fresh) {
            kept.entry(e).or_insert_with(|| Arc::new(c));
        }
        Ok(exprs
            .iter()
            .map(|e| kept.get(e).map_or_else(Vec::new, |c| c.as_ref().clone()))
            .collect())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    /// An expression is computed once, however many calls ask for it, and a call gets its
    /// columns in the order it asked.
    #[test]
    fn each_expression_is_computed_once() {
        let cache = ColumnCache::for_run(&[]);
        let asked = RefCell::new(Vec::new());
        let compute = |e: &[String]| {
            asked.borrow_mut().push(e.to_vec());
            Ok(e.iter().map(|x| vec![x.len() as f64]).collect())
        };
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let a = cache.columns(&s(&["ab", "c"]), compute).unwrap();
        assert_eq!(a, vec![vec![2.0], vec![1.0]]);
        let b = cache.columns(&s(&["c", "def", "def"]), compute).unwrap();
        assert_eq!(b, vec![vec![1.0], vec![3.0], vec![3.0]]);
        cache.columns(&s(&["def", "ab"]), compute).unwrap();
        assert_eq!(*asked.borrow(), vec![s(&["ab", "c"]), s(&["def"])]);
    }

    /// A run with gaps keeps nothing: every call computes what it asks, as it asks it.
    #[test]
    fn a_run_with_gaps_computes_every_call() {
        let cache = ColumnCache::for_run(&[0, 120]);
        let asked = RefCell::new(Vec::new());
        let compute = |e: &[String]| {
            asked.borrow_mut().push(e.to_vec());
            Ok(e.iter().map(|x| vec![x.len() as f64]).collect())
        };
        let s = vec!["ab".to_string(), "c".to_string()];
        cache.columns(&s, compute).unwrap();
        cache.columns(&s, compute).unwrap();
        assert_eq!(*asked.borrow(), vec![s.clone(), s]);
        assert!(ColumnCache::for_run(&[0]).0.is_some());
    }

    /// What the rule rests on, with the core's programs: on a run without gaps `rate(T)` computed
    /// beside a long lag is `rate(T)` computed alone; across a long gap it is not (the lag's time
    /// constant decides whether the program's filters restart).
    #[test]
    fn a_column_depends_on_its_program_only_across_gaps() {
        use tcomp_train::binning::bins;
        use tcomp_train::dataset::stretch_starts;
        let gappy = |gap: f64| {
            let time: Vec<f64> = (0..4000)
                .map(|i| f64::from(i) + if i >= 2000 { gap } else { 0.0 })
                .collect();
            let t: Vec<f64> = time
                .iter()
                .map(|s| 20.0 + 10.0 * (s / 900.0).sin())
                .collect();
            let data = tcomp_train::Dataset::from_columns(
                "run.csv",
                vec!["time_s".into(), "t".into()],
                vec![time.clone(), t],
            );
            let starts = stretch_starts(&time, Some(30.0));
            let b = bins(&time, 60.0);
            let col = |exprs: &[&str]| {
                let e: Vec<String> = exprs.iter().map(|x| x.to_string()).collect();
                crate::design::compute_binned(&[], &e, &data, "time_s", &starts, &b).unwrap()
            };
            let together = col(&["t", "rate(t)", "lag(t, 3000)"]);
            let alone = col(&["rate(t)"]);
            (
                ColumnCache::for_run(&starts).0.is_some(),
                together[1] == alone[0],
            )
        };
        assert_eq!(gappy(0.0), (true, true));
        // A 2,000 s gap: over 5 of rate's time constants, under 5 of the lag's.
        assert_eq!(gappy(2000.0), (false, false));
    }

    /// A failed computation keeps nothing: the next call computes again.
    #[test]
    fn a_failure_keeps_nothing() {
        let cache = ColumnCache::for_run(&[]);
        let s = vec!["x".to_string()];
        let err = cache.columns(&s, |_| {
            Err(crate::error::DiscoverError::Invalid("no".into()))
        });
        assert!(err.is_err());
        let ok = cache
            .columns(&s, |e| Ok(vec![vec![e.len() as f64]]))
            .unwrap();
        assert_eq!(ok, vec![vec![1.0]]);
    }
}
