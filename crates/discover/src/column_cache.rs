//! Binned columns of expressions already computed on one run, kept by expression.
//!
//! Why: a diagnosis scores the same expressions many times — the search over candidates, each
//! candidate's placebos, the surrogate fits of the confirmation, the dynamics' lag banks — and
//! running a feature program over every row of the run is most of what each score costs (a
//! fifth of a production line's calibration). A feature program computes each of its features
//! on its own (the signals they share are recomputed, not shared state), so the column of an
//! expression does not depend on the expressions computed beside it, and one kept from an
//! earlier call is the column a new call would compute.

use crate::error::Result;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

/// The columns of one run, by expression (see the module doc).
#[derive(Default)]
pub(crate) struct ColumnCache(Mutex<HashMap<String, Arc<Vec<f64>>>>);

impl ColumnCache {
    /// The columns of `exprs` in order: those kept, and the rest from `compute` (called once,
    /// with the missing expressions, each once, in their first order), which are then kept. An
    /// error of `compute` is returned as it is, and nothing of that call is kept.
    pub(crate) fn columns(
        &self,
        exprs: &[String],
        compute: impl FnOnce(&[String]) -> Result<Vec<Vec<f64>>>,
    ) -> Result<Vec<Vec<f64>>> {
        let missing: Vec<String> = {
            let kept = self.0.lock().unwrap_or_else(PoisonError::into_inner);
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
        let mut kept = self.0.lock().unwrap_or_else(PoisonError::into_inner);
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
        let cache = ColumnCache::default();
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

    /// A failed computation keeps nothing: the next call computes again.
    #[test]
    fn a_failure_keeps_nothing() {
        let cache = ColumnCache::default();
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
