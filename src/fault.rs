//! Fault injection for the tests of the parallel rule (a failure on one rank ends every rank
//! with the same message, no hang, nothing written), compiled only with the cargo feature
//! `fault-injection` (scripts/test builds with it; a plain `cargo build --release` has none of
//! it: [`injected`] is then `None` and [`limit`] the default, both constant).
//!
//! `SIGNORINI_TEST_FAULT=STAGE@RANK` makes [`injected`] report a failure at the stage named
//! STAGE on rank RANK only (a counted stage, below, also as `:panic` or `:petsc`). Stages: "mumps-rows" (a
//! rank hands its matrix rows to MUMPS), "nd-graph" (a rank reads its part of the node graph
//! for the nested-dissection order), "condensed-expand" (a rank takes its part of the
//! condensed path's expanded solution), "dense-steps" and "predictor-model" (rank 0 only: a
//! panic in the dense computation that the other ranks wait for).
//!
//! `SIGNORINI_TEST_FAULT=agree#N@RANK[:KIND]` strikes at the N-th agreement on that rank (every
//! guarded stage of every path ends in one), `petsc-call#N@RANK[:KIND]` at its N-th checked
//! PETSc call (a PETSc error on one rank at an arbitrary place, e.g. out of memory) ([`counted`]).
//!
//! `SIGNORINI_TEST_LIMIT_<NAME>=N` replaces a size limit of the solver by N ([`limit`]), so
//! that a small test mesh reaches the branch beyond it.

/// The environment variable that names the stage and the rank.
pub const VAR: &str = "SIGNORINI_TEST_FAULT";

/// How an injected fault strikes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The stage's own error path (a `RunError` on that rank).
    Error,
    /// A panic on that rank.
    Panic,
    /// A PETSc error raised on that rank alone.
    Petsc,
}

/// `Some(message)` when `SIGNORINI_TEST_FAULT` names `stage` and this `rank` (any kind).
/// Local; `None` without the feature.
pub fn injected(stage: &str, rank: usize) -> Option<String> {
    injected_kind(stage, rank).map(|(m, _)| m)
}

/// [`injected`] with the kind of the fault. Local.
#[cfg(feature = "fault-injection")]
pub fn injected_kind(stage: &str, rank: usize) -> Option<(String, Kind)> {
    matches(&std::env::var(VAR).ok()?, stage, rank)
}

/// Without the feature: never.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub fn injected_kind(_stage: &str, _rank: usize) -> Option<(String, Kind)> {
    None
}

/// At the `n`-th pass of this rank through the counted stage `stage` ("agree": an agreement of
/// [`crate::par::Ctx::agree`], "petsc-call": a checked PETSc call), when
/// `SIGNORINI_TEST_FAULT=STAGE#N@RANK[:KIND]` names it: the message and kind. Counts only
/// while the variable names `stage`. Local; `None` without the feature.
#[cfg(feature = "fault-injection")]
pub fn counted(stage: &str, rank: impl FnOnce() -> usize) -> Option<(String, Kind)> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::OnceLock;
    static SPEC: OnceLock<Option<(String, usize)>> = OnceLock::new();
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let spec = SPEC.get_or_init(|| {
        let v = std::env::var(VAR).ok()?;
        let (head, _) = v.split_once('@')?;
        let (s, n) = head.split_once('#')?;
        Some((s.to_string(), n.trim().parse().ok()?))
    });
    let (s, n) = spec.as_ref()?;
    if s != stage {
        return None;
    }
    let k = COUNT.fetch_add(1, Ordering::Relaxed) + 1;
    if k != *n {
        return None;
    }
    let value = std::env::var(VAR).ok()?;
    let (m, kind) = matches(&value, &format!("{stage}#{n}"), rank())?;
    Some((m, kind))
}

/// Without the feature: never.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub fn counted(_stage: &str, _rank: impl FnOnce() -> usize) -> Option<(String, Kind)> {
    None
}

/// The solver's size limit `name` (e.g. "MAX_SCHUR_DOFS"): `SIGNORINI_TEST_LIMIT_<name>` where
/// set (with the feature), else `default`. Local.
pub fn limit(name: &str, default: usize) -> usize {
    #[cfg(feature = "fault-injection")]
    if let Some(v) = std::env::var(format!("SIGNORINI_TEST_LIMIT_{name}"))
        .ok()
        .and_then(|v| v.trim().parse().ok())
    {
        return v;
    }
    let _ = name;
    default
}

/// The message and kind when `value` ("STAGE@RANK" or "STAGE@RANK:KIND") names `stage` and
/// `rank`.
#[cfg_attr(not(feature = "fault-injection"), allow(dead_code))]
fn matches(value: &str, stage: &str, rank: usize) -> Option<(String, Kind)> {
    let (s, r) = value.split_once('@')?;
    let (r, kind) = match r.split_once(':') {
        None => (r, Kind::Error),
        Some((r, "panic")) => (r, Kind::Panic),
        Some((r, "petsc")) => (r, Kind::Petsc),
        Some(_) => return None,
    };
    (s == stage && r.trim().parse::<usize>().ok()? == rank).then(|| {
        (
            format!("injected fault at {stage} on rank {rank} ({VAR})"),
            kind,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fires_only_at_its_stage_and_rank() {
        let v = "nd-graph@1";
        assert!(matches(v, "nd-graph", 1)
            .is_some_and(|(m, k)| m.contains("nd-graph on rank 1") && k == Kind::Error));
        assert_eq!(
            matches("nd-graph@1:panic", "nd-graph", 1).map(|(_, k)| k),
            Some(Kind::Panic)
        );
        assert_eq!(
            matches("nd-graph@0:petsc", "nd-graph", 0).map(|(_, k)| k),
            Some(Kind::Petsc)
        );
        assert!(matches("nd-graph@0:other", "nd-graph", 0).is_none());
        assert!(matches(v, "nd-graph", 0).is_none());
        assert!(matches(v, "mumps-rows", 1).is_none());
        assert!(matches("nd-graph", "nd-graph", 1).is_none());
        assert!(matches("nd-graph@x", "nd-graph", 1).is_none());
    }
}
