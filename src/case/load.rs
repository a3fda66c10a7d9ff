//! The `[load]` section: a quasi-static load history.
//!
//! ```toml
//! [load]
//! steps = 4                 # factors 1/4, 2/4, 3/4, 1 ...
//! # factors = [0.5, 1.0, 0.5]   # ... or the factors themselves (exactly one of the two)
//! max_cutbacks = 5          # halvings of a failing step in a row (default 5)
//! ```
//!
//! The Neumann data, the body force and the prescribed displacements are multiplied by the
//! factor of a step; the obstacle stays where it is. Factors are finite and ≥ 0, two steps in
//! a row differ, and the history may go up and down (unloading matters with friction) and
//! end anywhere: the run's final state is the one at the last factor.

use super::reader::{Reader, Res, Tab};
use super::tree::{join_index, Kind, Node};

/// Default of `load.max_cutbacks`.
pub const DEFAULT_MAX_CUTBACKS: usize = 5;
/// Largest `load.max_cutbacks` (2⁻³⁰ of a step is far below any useful increment).
pub const MAX_CUTBACKS_LIMIT: usize = 30;
/// Largest `load.steps` / number of `load.factors`.
pub const MAX_STEPS: usize = 100_000;

/// A validated load history.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadSection {
    /// The load factor of every step, in order.
    pub factors: Vec<f64>,
    /// Halvings of a failing step allowed in a row.
    pub max_cutbacks: usize,
}

impl LoadSection {
    /// One step at factor 1, no cutback: the static problem (the run without `[load]`).
    pub fn single() -> LoadSection {
        LoadSection {
            factors: vec![1.0],
            max_cutbacks: 0,
        }
    }
}

impl Reader<'_> {
    /// A non-negative integer no larger than `max`.
    fn count(&self, key: &str, n: &Node, min: i64, max: usize) -> Res<usize> {
        let Kind::Int(v) = n.kind else {
            return Err(self.type_err(key, n, "an integer"));
        };
        if v < min || v as u64 > max as u64 {
            return Err(self.err(
                key,
                n.loc,
                format!("must be an integer from {min} to {max}, got {v}"),
            ));
        }
        Ok(v as usize)
    }

    pub(super) fn load(&self, top: &Tab) -> Res<Option<LoadSection>> {
        let Some((k, n)) = top.get("load") else {
            return Ok(None);
        };
        let t = self.table(&k, n, super::keys::LOAD)?;
        let factors = match (t.get("steps"), t.get("factors")) {
            (Some((sk, s)), None) => {
                let steps = self.count(&sk, s, 1, MAX_STEPS)?;
                (1..=steps).map(|i| i as f64 / steps as f64).collect()
            }
            (None, Some((fk, f))) => self.factors(&fk, f)?,
            (Some(_), Some((fk, f))) => {
                return Err(self.err(
                    &fk,
                    f.loc,
                    "give either load.steps or load.factors, not both",
                ))
            }
            (None, None) => {
                return Err(self.err(
                    &k,
                    t.loc,
                    "[load] needs one of 'steps' (equal steps up to factor 1) or 'factors'",
                ))
            }
        };
        let max_cutbacks = match t.get("max_cutbacks") {
            Some((mk, m)) => self.count(&mk, m, 0, MAX_CUTBACKS_LIMIT)?,
            None => DEFAULT_MAX_CUTBACKS,
        };
        Ok(Some(LoadSection {
            factors,
            max_cutbacks,
        }))
    }

    /// `load.factors`: a non-empty array of finite numbers ≥ 0, no two in a row equal (0: only
    /// the loads with `ramp = false`).
    fn factors(&self, key: &str, n: &Node) -> Res<Vec<f64>> {
        let elems = self.array(key, n, "an array of load factors")?;
        if elems.is_empty() {
            return Err(self.err(key, n.loc, "must hold at least one load factor"));
        }
        if elems.len() > MAX_STEPS {
            return Err(self.err(
                key,
                n.loc,
                format!("at most {MAX_STEPS} load factors, got {}", elems.len()),
            ));
        }
        let mut out: Vec<f64> = Vec::with_capacity(elems.len());
        for (i, e) in elems.iter().enumerate() {
            let ek = join_index(key, i);
            let x = self.num(&ek, e)?;
            if x < 0.0 {
                return Err(self.err(&ek, e.loc, format!("must be ≥ 0, got {x}")));
            }
            if out.last() == Some(&x) {
                return Err(self.err(
                    &ek,
                    e.loc,
                    format!("equals the factor before it ({x}): every step must change the load"),
                ));
            }
            out.push(x);
        }
        Ok(out)
    }
}
