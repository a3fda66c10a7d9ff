//! What the Schur path reports: the summaries of the frictionless and Coulomb passes
//! (summary.json's `condensed` object) and the dense steps recorded into the history and log.

use super::candidates::{Candidates, Compliance};
use crate::par::Ctx;
use crate::say;
use crate::signorini::dense::DenseRun;
use crate::signorini::plain_path::StepInfo;
use crate::signorini::step_system::SolveKind;
use serde::Serialize;

/// summary.json's `newton.condensed`: what the condensed path did.
#[derive(Debug, Clone, Serialize)]
pub struct CondensedSummary {
    /// The path ran to the end ("condensed"), or handed the solve to the plain path
    /// ("fallback", with the reason).
    pub outcome: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback_reason: Option<String>,
    /// Candidate contact nodes (the dense system's size).
    pub candidates: usize,
    /// Variables of the Schur complement (every dof of every candidate), last round.
    pub schur_dofs: usize,
    /// Numeric factorisations of K_p with the Schur complement (one per round of candidates).
    pub factorisations: usize,
    /// The fill-reducing order, MUMPS' analysis and numeric factorisation of K_p with the
    /// Schur complement [s].
    pub factorisation_seconds: f64,
    /// Of which the nested-dissection order of K_p's node graph (Scotch on rank 0) [s].
    pub ordering_seconds: f64,
    /// MUMPS' estimate of the flops of those factorisations (RINFOG(1), summed).
    pub factorisation_flops: f64,
    /// The entries in the last factorisation's factors (INFOG(29)).
    pub factor_entries: i64,
    /// Handing K_p to MUMPS, the condensation of f, the dense factorisation of S, C and d₀ [s].
    pub schur_seconds: f64,
    /// Algorithm 1's steps on the dense system [s].
    pub dense_seconds: f64,
    /// The expansion solve, (3.28) and the check of the final set [s].
    pub expansion_seconds: f64,
    /// Solve phases with the factorisation (condensations, expansions).
    pub solves: usize,
    /// A load step on the previous load step's factorisation (`factorisations` 0).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub factorisation_kept: bool,
    /// The nested start (newton.init = "auto", no warm start): per coarse level, coarsest
    /// first, its nodes and Algorithm 1's steps on it (dense; not counted in newton.steps).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub coarse_levels: Vec<CoarseLevel>,
    /// Coulomb's generalised Newton on the same candidates (friction, held bodies).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coulomb: Option<CoulombCondensedSummary>,
    /// The fallback came from the dense limits (the candidates' Schur dofs, the dense work
    /// against the factorisation's): the contact zone is too wide for the dense compliance.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub too_wide: bool,
    /// The dense steps ran in the primal form on S (dense::Primal): C = S⁻¹ would have cost
    /// more than the factorisation.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub primal: bool,
    /// A wide zone's interior held on the obstacle in K_p (the last pass; 0: none).
    #[serde(skip_serializing_if = "is_zero")]
    pub held_nodes: usize,
    /// Which nodes: [`tag_key`] of their gmsh tags (the last pass; absent: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_key: Option<u64>,
    /// Which nodes were the candidates (the last round): [`tag_key`] of their gmsh tags.
    pub candidates_key: u64,
}

/// A key of a set of contact nodes that does not depend on the partition or on the order the
/// nodes come in: the wrapping sum of a mix (splitmix64's finaliser) of their gmsh tags. Two
/// runs that held or took different nodes differ in it (but for a 2⁻⁶⁴ chance). Local.
pub fn tag_key(tags: impl Iterator<Item = u64>) -> u64 {
    tags.map(|t| {
        let mut z = t.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    })
    .fold(0u64, u64::wrapping_add)
}

pub(crate) fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One coarse level of the nested start.
#[derive(Debug, Clone, Serialize)]
pub struct CoarseLevel {
    pub nodes: usize,
    pub steps: usize,
}

impl CondensedSummary {
    pub(crate) fn new(candidates: usize) -> CondensedSummary {
        CondensedSummary {
            outcome: "condensed",
            fallback_reason: None,
            candidates,
            schur_dofs: 0,
            factorisations: 0,
            factorisation_seconds: 0.0,
            ordering_seconds: 0.0,
            factorisation_flops: 0.0,
            factor_entries: 0,
            schur_seconds: 0.0,
            dense_seconds: 0.0,
            expansion_seconds: 0.0,
            solves: 0,
            factorisation_kept: false,
            coarse_levels: Vec::new(),
            coulomb: None,
            too_wide: false,
            primal: false,
            held_nodes: 0,
            held_key: None,
            candidates_key: 0,
        }
    }

    /// A round's factorisation into the record: `seconds` of the round so far, of which
    /// `comp.factorisation_seconds` the ordering, analysis and factorisation.
    pub(super) fn record_factorisation(
        &mut self,
        comp: &Compliance,
        cand: &Candidates,
        seconds: f64,
    ) {
        self.factorisations += 1;
        self.solves += 1;
        self.factorisation_seconds += comp.factorisation_seconds;
        self.factorisation_flops += comp.stats.flops;
        self.factor_entries = comp.stats.factor_entries;
        self.ordering_seconds = self.ordering_seconds.max(comp.ordering_seconds);
        self.schur_seconds += seconds - comp.factorisation_seconds;
        self.candidates = comp.list.len();
        self.candidates_key = tag_key(comp.list.iter().map(|&i| cand.tag(i)));
        self.schur_dofs = comp.list.len() * comp.per;
    }

    /// A load step on the previous step's factorisation into the record and the log: one
    /// condensation (`seconds`), no factorisation.
    pub(super) fn record_kept(
        &mut self,
        ctx: &Ctx,
        comp: &Compliance,
        cand: &Candidates,
        seconds: f64,
    ) {
        self.solves += 1;
        self.schur_seconds += seconds;
        self.candidates = comp.list.len();
        self.candidates_key = tag_key(comp.list.iter().map(|&i| cand.tag(i)));
        self.schur_dofs = comp.list.len() * comp.per;
        say!(
            ctx,
            "newton: condensed: the previous load step's factorisation and compliance on {} \
             candidates, d₀ of this step ({seconds:.3} s)",
            self.candidates
        );
    }

    /// The nested start's coarse levels of a dense round, into the record and the log.
    pub(super) fn record_coarse(&mut self, ctx: &Ctx, run: &DenseRun) {
        if run.coarse.is_empty() {
            return;
        }
        let levels: Vec<String> = run
            .coarse
            .iter()
            .map(|c| format!("{} nodes {} steps", c.0, c.1))
            .collect();
        say!(
            ctx,
            "newton: condensed: nested start on coarse subsets of the candidates: {}",
            levels.join(", ")
        );
        self.coarse_levels.extend(
            run.coarse
                .iter()
                .map(|&(nodes, steps)| CoarseLevel { nodes, steps }),
        );
    }

    /// The closing log line of a converged condensed solve (`n` contact nodes).
    pub(super) fn log(&self, ctx: &Ctx, n: usize, active: usize) {
        let factorisation = self.factorisation_said();
        let form = if self.primal {
            " (primal form on S)"
        } else {
            ""
        };
        say!(
            ctx,
            "newton: condensed: {} of {n} contact nodes as candidates, {active} active, \
             {factorisation}, Schur complement {:.3} s, dense{form} {:.3} s, expansion {:.3} s",
            self.candidates,
            self.schur_seconds,
            self.dense_seconds,
            self.expansion_seconds
        );
    }

    /// The log line of a solve that stops after its factorisation (no frictionless steps: a
    /// friction solve's warm pass or load step goes on from its own start; `n` contact nodes).
    pub(super) fn log_factorised(&self, ctx: &Ctx, n: usize) {
        say!(
            ctx,
            "newton: condensed: {} of {n} contact nodes as candidates, {}, Schur complement \
             {:.3} s; the friction iteration from its warm states",
            self.candidates,
            self.factorisation_said(),
            self.schur_seconds
        );
    }

    /// The factorisation as the log lines say it.
    fn factorisation_said(&self) -> String {
        if self.factorisation_kept {
            "the previous load step's factorisation".to_string()
        } else {
            format!(
                "factorisation {:.3} s (ordering {:.3} s, {:.3e} flops, {} factor entries)",
                self.factorisation_seconds,
                self.ordering_seconds,
                self.factorisation_flops,
                self.factor_entries
            )
        }
    }
}

/// The dense steps of one round (`steps`: number, |A_n|, changed, residual, seconds) into the
/// history (numbered on) and the log, which names the residual and the path (`residual`,
/// `path`: "C_n", "condensed"; "C", "condensed Coulomb" or "condensed Tresca"). Collective
/// (log).
pub(crate) fn record_steps(
    ctx: &Ctx,
    history: &mut Vec<StepInfo>,
    steps: &[(usize, usize, usize, f64, f64)],
    residual: &str,
    path: &str,
    candidates: usize,
    pinned: usize,
) {
    let base = history.len();
    for h in steps {
        say!(
            ctx,
            "newton {:3}: |A_n| = {:6}  changed {:6}  |{residual}| = {:.3e}  {path}, \
             {candidates} candidates ({:.4} s)",
            base + h.0,
            h.1,
            h.2,
            h.3,
            h.4
        );
        history.push(StepInfo {
            step: base + h.0,
            active: h.1,
            changed: h.2,
            residual: h.3,
            solve_seconds: h.4,
            solve: SolveKind::Condensed,
            iterations: 0,
            reuse: None,
            amg: None,
            pinned,
            states: None,
            du_rel: None,
            predictor: None,
            change: None,
            factorisation_seconds: None,
        });
    }
}

/// summary.json's `newton.condensed.coulomb`: what the dense Coulomb iteration did.
#[derive(Debug, Clone, Serialize)]
pub struct CoulombCondensedSummary {
    /// The law iterated ("coulomb", or "tresca": Algorithm 2 with b_k fixed).
    pub law: &'static str,
    /// "condensed": the expanded iterate passed the check; "start": it became the plain
    /// path's start (`reason` says why); "fallback": the dense iteration gave up (`reason`).
    pub outcome: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Steps of the dense generalised Newton.
    pub steps: usize,
    /// Of these, the steps solved in the primal form (on S itself; the others on C = S⁻¹).
    pub primal_steps: usize,
    pub dense_seconds: f64,
    /// The expansion solve, (3.28) and the check on every contact node [s].
    pub expansion_seconds: f64,
    /// The nested start (from the frictionless solution): per coarse level, coarsest first,
    /// its candidates and dense steps (not in `steps`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub coarse_levels: Vec<CoarseLevel>,
    /// The dense step whose settled slip rows left its system singular, from which the (F5)
    /// rows ran (docs/friction.md, "A singular dense step"); absent where none did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f5_from: Option<usize>,
    /// The nested start's coarse levels on which the same happened.
    #[serde(skip_serializing_if = "is_zero")]
    pub f5_coarse_levels: usize,
    /// Tresca's nodes with a threshold beyond the candidates, whose friction was a load
    /// (docs/friction.md, "Tresca's far nodes"); absent where there were none.
    #[serde(skip_serializing_if = "is_zero")]
    pub far_nodes: usize,
    /// The rounds of the dense iteration that found their friction (each one condensation and
    /// one expansion solve on the kept factorisation).
    #[serde(skip_serializing_if = "is_zero")]
    pub far_rounds: usize,
}
