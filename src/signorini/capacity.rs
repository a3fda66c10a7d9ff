//! A frictional body's friction capacity checked before the solve (a floating body against
//! parallel planes), and what a failed iteration of a sliding body says.

use super::boundary::ContactBoundary;
use super::force;
use super::law::{FloatingLoad, Law};
use crate::assembly::System;
use crate::contact::Obstacle;
use crate::error::RunError;
use crate::par::Ctx;

/// A floating body (no Dirichlet data) against planes that share one normal direction (a plane,
/// or a body between parallel plates) has no equilibrium when the tangential resultant of its
/// load exceeds the total friction capacity of its pairs: Tresca Σ_k b_k (3.18); Coulomb
/// Σ_j μ_j N_j with N_j the pair's normal force, μ (−λ_n^k) summed over the pair's nodes. N_j is
/// known where the pair is under a force along its normal (N_j = |F_j|) or is the one pair left
/// to balance the load's normal resultant. Said before the solve instead of after a long (or
/// cycling) Newton run; other settings (tilted planes, curved obstacles, slanted forces, two
/// pairs with unknown normal forces) are left to the iteration. Returns whether the load was
/// found within the capacity (an equilibrium of the rigid motion exists). Collective.
pub fn check_friction_capacity(
    ctx: &Ctx,
    b: &ContactBoundary,
    fixed: &[f64],
    sys: &System,
    dim: usize,
    law: Law,
    forces: &[force::ForceControl],
) -> Result<bool, RunError> {
    let Some(planes) = parallel_planes(&b.obstacles) else {
        return Ok(false);
    };
    if !law.friction() || held_anywhere(ctx, fixed) {
        return Ok(false);
    }
    let np = planes.len();
    // per pair: max μ (Coulomb) and Σ b_k (Tresca) over its nodes
    let mut local = vec![0.0; 2 * np];
    for k in &b.nodes {
        local[2 * k.pair] = f64::max(local[2 * k.pair], k.mu);
        local[2 * k.pair + 1] += k.bound;
    }
    let mu: Vec<f64> = (0..np).map(|j| ctx.max_f64(local[2 * j])).collect();
    let bounds = ctx.sum_vec(
        &local
            .iter()
            .skip(1)
            .step_by(2)
            .copied()
            .collect::<Vec<f64>>(),
    );
    let f = sys.b.to_local_vec()?;
    let mut local = [0.0; 3];
    for (i, x) in f.iter().enumerate() {
        local[i % dim] += x;
    }
    let r = ctx.sum_vec(&local);
    let n0 = planes[0];
    let rn = (0..3).map(|k| r[k] * n0[k]).sum::<f64>();
    let rt = (0..3)
        .map(|k| (r[k] - rn * n0[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    let load = FloatingLoad {
        planes: &planes,
        rn,
        forces,
        mu: &mu,
        bounds: &bounds,
    };
    let Some((capacity, what)) = law.rules().capacity(&load) else {
        return Ok(false); // not known before the solve: the balance test and the iteration decide
    };
    if rt > capacity * (1.0 + 1e-9) + 1e-14 * r.iter().map(|x| x.abs()).sum::<f64>() {
        return Err(RunError::Failed(format!(
            "no equilibrium: the body has no Dirichlet data and the tangential resultant of its \
             load ({rt:.6e}) exceeds the total friction capacity of the contact boundary \
             ({what}): it would slide away"
        )));
    }
    Ok(true)
}

/// A failed iteration (`NoConvergence`) of a frictional case with a body that Dirichlet data
/// leave free in some rigid mode (`sliding`) says what may be the cause; `within`: its load
/// was found within the friction capacity before the solve ([`check_friction_capacity`]),
/// so an equilibrium exists and the iteration fell short of it. Other errors as they are.
pub fn why_sliding(e: RunError, sliding: bool, within: bool) -> RunError {
    match e {
        RunError::NoConvergence(why) if sliding && within => RunError::NoConvergence(format!(
            "{why}; a body of the mesh is free to move where its Dirichlet data do not hold \
             it and friction alone holds it tangentially, with its load within the friction \
             capacity of its contact (checked before the solve): an equilibrium exists, the \
             iteration did not reach it (more steps: newton.max_steps; the condensed path: \
             solver.path = \"auto\" on the direct preset)"
        )),
        RunError::NoConvergence(why) if sliding => RunError::NoConvergence(format!(
            "{why}; a body of the mesh is free to move where its Dirichlet data do not hold \
             it, so friction alone holds it tangentially: beyond the friction capacity of its \
             contact (not known before the solve on curved or non-parallel obstacles, or \
             between bodies) it has no equilibrium"
        )),
        e => e,
    }
}

/// A failed iteration (`NoConvergence`) of a case with a body pair whose slave side is
/// [`STIFF_SLAVE_RATIO`](crate::tuning::STIFF_SLAVE_RATIO) or more times as stiff as its
/// master (`slave_over_master`, the contact moduli at the two groups) says so: the dual
/// mortar's node-wise conditions sit on the slave nodes, and a stiff slave side pressed into
/// a soft master leaves their states to the soft side's deformation. Measured: a quarter ball
/// of E = 1e6 as the slave on a block of E = 1 (3D) did not converge in 400 Newton steps on
/// either path or preset, the same pair with the block as the slave in 1 step. Other errors as
/// they are.
pub fn why_stiff_slave(e: RunError, slave_over_master: Option<f64>) -> RunError {
    match (e, slave_over_master) {
        (RunError::NoConvergence(why), Some(r)) if r >= crate::tuning::STIFF_SLAVE_RATIO => {
            RunError::NoConvergence(format!(
                "{why}; the slave side of a body pair is {r:.3e} times as stiff as its master \
                 (contact moduli): body pairs converge best with the softer side as the slave \
                 (swap contact.group and contact.obstacle.group)"
            ))
        }
        (e, _) => e,
    }
}

/// Some dof of the mesh has Dirichlet data (`fixed` covers each rank's local mesh: agreed by
/// one reduction). Collective.
pub fn held_anywhere(ctx: &Ctx, fixed: &[f64]) -> bool {
    let here = if fixed.iter().any(|x| !x.is_nan()) {
        1.0
    } else {
        0.0
    };
    ctx.max_f64(here) > 0.0
}

/// The normals (into the body) of the pairs' obstacles if every one is a plane and all are
/// parallel (n_j = ±n_0).
fn parallel_planes(obstacles: &[Obstacle]) -> Option<Vec<[f64; 3]>> {
    let normals: Vec<[f64; 3]> = obstacles
        .iter()
        .map(|o| match o {
            Obstacle::Plane(p) => Some(p.normal()),
            _ => None,
        })
        .collect::<Option<_>>()?;
    let n0 = *normals.first()?;
    normals
        .iter()
        .all(|n| crate::geom::dot(*n, n0).abs() >= 1.0 - 1e-12)
        .then_some(normals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_parallel_planes_have_a_capacity_before_the_solve() {
        let plane = |n: [f64; 3]| {
            Obstacle::Plane(crate::contact::Plane::new([0.0; 3], n, 2).expect("plane"))
        };
        let two = [plane([0.0, 1.0, 0.0]), plane([0.0, -1.0, 0.0])];
        assert_eq!(parallel_planes(&two).map(|v| v.len()), Some(2));
        let tilted = [plane([0.0, 1.0, 0.0]), plane([0.6, -0.8, 0.0])];
        assert_eq!(parallel_planes(&tilted), None);
    }

    #[test]
    fn a_failed_body_pair_with_a_stiff_slave_side_says_so() {
        let failed = || RunError::NoConvergence("Newton did not converge".into());
        let hinted = why_stiff_slave(failed(), Some(1e6)).to_string();
        assert!(hinted.contains("1.000e6 times as stiff"), "{hinted}");
        assert!(hinted.contains("contact.obstacle.group"), "{hinted}");
        for ratio in [None, Some(1.0), Some(99.0)] {
            assert_eq!(
                why_stiff_slave(failed(), ratio).to_string(),
                "Newton did not converge"
            );
        }
        let other = why_stiff_slave(RunError::Failed("x".into()), Some(1e6));
        assert_eq!(other.to_string(), "x");
    }
}
