//! A frictional body's friction capacity checked before the solve (a floating body against
//! parallel planes), and what a failed iteration of a sliding body says.

use super::active_set::Law;
use super::boundary::ContactBoundary;
use super::force;
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
/// pairs with unknown normal forces) are left to the iteration. Collective.
pub fn check_friction_capacity(
    ctx: &Ctx,
    b: &ContactBoundary,
    (fixed, sys, dim): (&[f64], &System, usize),
    law: Law,
    forces: &[force::ForceControl],
) -> Result<(), RunError> {
    let Some(planes) = parallel_planes(&b.obstacles) else {
        return Ok(());
    };
    if law == Law::Frictionless || held_anywhere(ctx, fixed) {
        return Ok(());
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
    let (capacity, what) = if law == Law::Tresca {
        let c: f64 = bounds.iter().sum();
        if c == 0.0 {
            return Ok(()); // frictionless: the balance test of the free modes decides
        }
        (c, format!("Σ b_k = {c:.6e}, (3.18)"))
    } else {
        let Some(normal) = normal_forces(&planes, rn, forces) else {
            return Ok(());
        };
        let c: f64 = normal.iter().zip(&mu).map(|(n, m)| n * m).sum();
        if c <= 0.0 {
            return Ok(()); // no friction, or no normal load: the balance test decides
        }
        let terms: Vec<String> = normal
            .iter()
            .zip(&mu)
            .filter(|(n, _)| **n > 0.0)
            .map(|(n, m)| format!("{m} × {n:.6e}"))
            .collect();
        let what = if np == 1 {
            format!(
                "μ Σ_k (−λ_n^k) = μ × normal load = {} = {c:.6e}, Coulomb",
                terms.join("")
            )
        } else {
            format!(
                "Σ_j μ_j N_j over the pairs, N_j their normal forces = {} = {c:.6e}, Coulomb",
                terms.join(" + ")
            )
        };
        (c, what)
    };
    if rt > capacity * (1.0 + 1e-9) + 1e-14 * r.iter().map(|x| x.abs()).sum::<f64>() {
        return Err(RunError::Failed(format!(
            "no equilibrium: the body has no Dirichlet data and the tangential resultant of its \
             load ({rt:.6e}) exceeds the total friction capacity of the contact boundary \
             ({what}): it would slide away"
        )));
    }
    Ok(())
}

/// A failed iteration (`NoConvergence`) of a frictional body without Dirichlet data
/// (`sliding`) says what may be the cause; other errors as they are.
pub fn why_sliding(e: RunError, sliding: bool) -> RunError {
    match e {
        RunError::NoConvergence(why) if sliding => RunError::NoConvergence(format!(
            "{why}; the body has no Dirichlet data, so friction alone holds it tangentially: \
             beyond the friction capacity of its contact (not known before the solve on curved \
             or non-parallel obstacles) it has no equilibrium"
        )),
        e => e,
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

/// The pairs' normal forces N_j ≥ 0 on a floating body between parallel planes (normals
/// `planes`, n_j = s_j n_0), from the load's normal resultant `rn` (along n_0) and the forces
/// under control: Σ_j s_j N_j + rn = 0, N_j = |F_j| on a pair pushed along its normal. `None`
/// if a force is not along its plane's normal, if more than one pair's force is unknown, or
/// if the balance asks for a pull (N < 0: the body leaves the plane, the balance test decides).
fn normal_forces(planes: &[[f64; 3]], rn: f64, forces: &[force::ForceControl]) -> Option<Vec<f64>> {
    let n0 = planes[0];
    let s: Vec<f64> = planes
        .iter()
        .map(|n| crate::geom::dot(*n, n0).signum())
        .collect();
    let mut normal = vec![f64::NAN; planes.len()];
    for fc in forces {
        let along = crate::geom::dot(fc.direction(), planes[fc.pair]);
        if along < 1.0 - 1e-12 {
            return None;
        }
        normal[fc.pair] = fc.magnitude();
    }
    let unknown: Vec<usize> = (0..planes.len()).filter(|&j| normal[j].is_nan()).collect();
    let known: f64 = (0..planes.len())
        .filter(|&j| !normal[j].is_nan())
        .map(|j| s[j] * normal[j])
        .sum();
    match unknown.as_slice() {
        [] => {}
        [u] => normal[*u] = -(rn + known) / s[*u],
        _ => return None,
    }
    normal.iter().all(|&n| n >= 0.0).then_some(normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pushed(pair: usize, force: [f64; 3]) -> force::ForceControl {
        force::ForceControl {
            force,
            start: 0.0,
            file: "case.toml".into(),
            pair,
            key: format!("contact[{pair}].force"),
        }
    }

    /// The normal forces of a body between a plate below (n = +y) and one above (n = −y).
    #[test]
    fn normal_forces_between_two_plates() {
        let plates = [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]];
        // the top plate pushed down by 0.01, a body load of 0.002 downwards (rn = −0.002)
        let top = [pushed(1, [0.0, -0.01, 0.0])];
        let n = normal_forces(&plates, -0.002, &top).expect("known");
        assert!((n[0] - 0.012).abs() < 1e-15 && n[1] == 0.01, "{n:?}");
        // one plane, no force: N = −rn; a pull leaves it to the balance test
        assert_eq!(normal_forces(&plates[..1], -0.5, &[]), Some(vec![0.5]));
        assert_eq!(normal_forces(&plates[..1], 0.5, &[]), None);
        // two unknown normal forces, or a slanted force: not known before the solve
        assert_eq!(normal_forces(&plates, -0.002, &[]), None);
        let slanted = [pushed(1, [0.001, -0.01, 0.0])];
        assert_eq!(normal_forces(&plates, -0.002, &slanted), None);
    }

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
}
