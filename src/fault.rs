//! Fault injection for the tests of the parallel rule (a failure on one rank ends every rank
//! with the same message, no hang, nothing written): `SIGNORINI_TEST_FAULT=STAGE@RANK` makes
//! [`injected`] report a failure at the stage named STAGE on rank RANK only. Unset (every real
//! run), it never fires. Stages: "mumps-rows" (a rank hands its matrix rows to MUMPS),
//! "nd-graph" (a rank reads its part of the node graph for the nested-dissection order),
//! "condensed-expand" (a rank takes its part of the condensed path's expanded solution),
//! "dense-steps" and "predictor-model" (rank 0 only: a panic in the dense computation that
//! the other ranks wait for).

/// The environment variable that names the stage and the rank.
pub const VAR: &str = "SIGNORINI_TEST_FAULT";

/// `Some(message)` when `SIGNORINI_TEST_FAULT` names `stage` and this `rank`. Local.
pub fn injected(stage: &str, rank: usize) -> Option<String> {
    matches(&std::env::var(VAR).ok()?, stage, rank)
}

/// The message when `value` ("STAGE@RANK") names `stage` and `rank`.
fn matches(value: &str, stage: &str, rank: usize) -> Option<String> {
    let (s, r) = value.split_once('@')?;
    (s == stage && r.trim().parse::<usize>().ok()? == rank)
        .then(|| format!("injected fault at {stage} on rank {rank} ({VAR})"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fires_only_at_its_stage_and_rank() {
        let v = "nd-graph@1";
        assert!(matches(v, "nd-graph", 1).is_some_and(|m| m.contains("nd-graph on rank 1")));
        assert!(matches(v, "nd-graph", 0).is_none());
        assert!(matches(v, "mumps-rows", 1).is_none());
        assert!(matches("nd-graph", "nd-graph", 1).is_none());
        assert!(matches("nd-graph@x", "nd-graph", 1).is_none());
    }
}
