//! The final state judged: the contact table, the KKT certificate of (3.14) and, with friction,
//! the friction certificate of (3.18) against the problem's scales, and the final certificate
//! (certificate.rs) of a solve.

use super::boundary::{CaseKeys, ContactBoundary, NodeResult};
use super::certificate;
use super::force;
use super::law::{Coulomb, FrictionLaw};
use super::plain_path::{ContactProblem, NewtonResult};
use super::report::{self, ContactSummary, FrictionCertificate, Kkt, Scales};
use crate::assembly::System;
use crate::error::RunError;
use crate::mortar::InU;
use crate::par::Ctx;
use crate::petsc::Vector;
use crate::say;
use crate::setup::ContactSettings;
use crate::warnings::{self, Warning};
use serde::Serialize;

/// A solve's final state as [`final_state`] judged it: the gathered contact table and
/// summary.json's "contact" section (with the KKT and friction certificates and the scales).
pub struct FinalState {
    pub contact: ContactSummary,
    pub table: report::Table,
    /// [`warnings::INEXACT_FINAL_STATE`] where the certificates exceed round-off (not logged
    /// yet).
    pub warning: Option<Warning>,
    /// The least reference the certificate judges the equilibrium by: a load step's, the step
    /// before's ([`certificate::Equilibrium::floored`]); 0 for a single solve.
    pub equilibrium_floor: f64,
}

/// The final state: the contact table, the KKT and friction certificates (an error if they
/// fail), the contact line of the log and summary.json's "contact" section. Collective.
pub fn final_state(
    ctx: &Ctx,
    sys: &System,
    b: &ContactBoundary,
    nr: &NewtonResult,
    friction: bool,
    dim: usize,
    floor: Scales,
) -> Result<FinalState, RunError> {
    let table = report::gather(ctx, b, &nr.nodes, dim);
    let total_force = report::total_force(ctx, &nr.nodes);
    let half_width = match b.obstacles.as_slice() {
        [one] => table.half_width(one, None),
        _ => None,
    };
    let (scales, kkt, friction_certificate) =
        certificates(ctx, sys, &table, &nr.u, friction, floor)?;
    let warning = check_certificates(&kkt, friction_certificate.as_ref(), &scales, &b.keys)?;
    say!(
        ctx,
        "contact: {} active, p_max = {:.6}, half width = {}, total force = {:?}",
        table.active_count(),
        table.max_pressure(),
        half_width
            .map(|b| format!("{b:.6}"))
            .unwrap_or_else(|| "n/a".into()),
        &total_force[..dim]
    );
    let contact = ContactSummary {
        nodes: b.n_global,
        excluded_dirichlet: b.excluded_dirichlet,
        active_count: table.active_count(),
        max_pressure: table.max_pressure(),
        total_force: total_force[..dim].to_vec(),
        obstacle_displacement: None,
        approach: None,
        half_width,
        pairs: None,
        kkt,
        friction: friction_certificate,
        scales,
    };
    Ok(FinalState {
        contact,
        table,
        warning,
        equilibrium_floor: 0.0,
    })
}

/// The final state's certificate (certificate.rs): the stop rule, (3.14), (3.18), the global
/// equilibrium and each force-controlled pair's balance, said in one log line; with
/// `newton.strict` an error where the rule is loosened or a relative value above
/// [`certificate::STRICT_TOL`]; `problem`'s boundary the judged one, `in_u` the body pairs'
/// view of the problem in u. Collective.
pub fn certify(
    ctx: &Ctx,
    settings: &ContactSettings,
    problem: &ContactProblem,
    state: &FinalState,
    nr: &NewtonResult,
    in_u: Option<&InU>,
    force_control: &[force::ForceControl],
) -> Result<certificate::Certificate, RunError> {
    let (b, sys) = (problem.boundary, problem.sys);
    let (table, contact) = (&state.table, &state.contact);
    let elastic = certificate::Elastic {
        mesh: problem.mesh,
        layout: problem.layout,
        material: &settings.material,
        fixed: problem.fixed,
    };
    let (equilibrium, lambdas) = match in_u {
        None => certificate::equilibrium(ctx, &elastic, &sys.a, &sys.b, &[], b, &nr.u)?,
        // body pairs: the balance of the bodies in u (the slave nodes' forces reach the
        // master rows)
        Some(p) => {
            let (a, rows) = (p.basis.a(), p.basis.master_rows());
            certificate::equilibrium(ctx, &elastic, a, p.f, rows, b, &p.u(&nr.u)?)?
        }
    };
    // judged as the KKT certificate is: against the problem's force scale too (|f|∞ of the
    // eliminated system, else the contact's own). The block of tests/cases/block2d_pulled.toml
    // on the iterative preset, moved by its Dirichlet data alone: a residual of 1.6e-12 (the
    // Krylov tolerance) against forces of round-off, 2.4e-6 of the floor of its operands'
    // round-off, 4.8e-11 of the force scale 0.033
    let equilibrium =
        (equilibrium.floored(state.equilibrium_floor)).floored(contact.kkt.force_scale);
    let force_balance = (!force_control.is_empty())
        .then(|| certificate::force_balance(ctx, b, &lambdas, force_control));
    let cert = certificate::Certificate::new(certificate::Parts {
        stop: nr.stop,
        strict: settings.newton.strict,
        kkt: &contact.kkt,
        friction: contact.friction.as_ref(),
        scales: &contact.scales,
        mesh_size: table.mesh_size(),
        equilibrium,
        force_balance,
    });
    say!(ctx, "{}", cert.line());
    match cert.strict_failure().filter(|_| cert.strict) {
        Some(why) => Err(RunError::Failed(why)),
        None => Ok(cert),
    }
}

/// The worst violation of (3.14) and of Coulomb's (3.18) with b_k = μ(−λ_n^k) by a state
/// (`nodes`, `u`) relative to the problem's scales, as [`final_state`] judges the final one (it
/// warns beyond 1e-8). Collective (one all-gather, two reductions).
pub fn coulomb_certificate_worst(
    ctx: &Ctx,
    sys: &System,
    b: &ContactBoundary,
    nodes: &[NodeResult],
    u: &Vector,
    dim: usize,
) -> Result<f64, RunError> {
    let mut judged = b.clone();
    judged_bounds(&Coulomb, &mut judged, nodes);
    let table = report::gather(ctx, &judged, nodes, dim);
    let (scales, kkt, friction) = certificates(ctx, sys, &table, u, true, Scales::default())?;
    let friction = friction.map_or(0.0, |f| f.worst(&scales));
    Ok(kkt.worst().max(friction))
}

/// The thresholds b_k by which the certificates and the output judge the law `law` at the
/// state `nodes` (Coulomb: b_k = μ(−λ_n^k) (F1); the boundary's own otherwise). Local.
pub fn judged_bounds(law: &dyn FrictionLaw, b: &mut ContactBoundary, nodes: &[NodeResult]) {
    for (k, r) in b.nodes.iter_mut().zip(nodes) {
        k.bound = law.judged_bound(k, r);
    }
}

/// The problem's scales, at least `floor`, the KKT certificate of (3.14) and, with friction,
/// the friction certificate of (3.18) of a gathered contact table at u. Collective (two
/// reductions).
fn certificates(
    ctx: &Ctx,
    sys: &System,
    table: &report::Table,
    u: &Vector,
    friction: bool,
    floor: Scales,
) -> Result<(Scales, report::Kkt, Option<report::FrictionCertificate>), RunError> {
    let scales = problem_scales(ctx, sys, u)?;
    let mut kkt = table.kkt(!friction, &scales);
    kkt.force_scale = kkt.force_scale.max(floor.force);
    kkt.length_scale = kkt.length_scale.max(floor.length);
    // without a load (a body moved by its Dirichlet data or by the obstacle alone) the force
    // scale is the contact's own, as the KKT certificate takes it: friction with μ = 0 or
    // g_R = 0 (b = 0) is judged by it too, not by a zero scale
    let scales = Scales {
        force: kkt.force_scale,
        length: scales.length.max(floor.length),
    };
    Ok((scales, kkt, friction.then(|| table.friction_certificate())))
}

/// |f|_∞ and |u|_∞ of the whole problem (two reductions); a non-finite u is an error.
fn problem_scales(ctx: &Ctx, sys: &System, u: &Vector) -> Result<Scales, RunError> {
    let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let u_local = u.to_local_vec()?;
    let length = ctx.max_f64(if u_local.iter().all(|x| x.is_finite()) {
        inf(&u_local)
    } else {
        f64::INFINITY
    });
    if !length.is_finite() {
        return Err(RunError::Failed(
            "the final displacement is not finite (the reduced system was singular or the \
             iteration diverged)"
                .into(),
        ));
    }
    let force = ctx.max_f64(inf(&sys.b.to_local_vec()?));
    Ok(Scales { force, length })
}

/// The final state against (3.14) (and (3.18) with friction): beyond
/// [`warnings::CERTIFICATE_ROUND_OFF`] of the problem's scales a warning (an inexact linear
/// solve), beyond [`report::CERTIFICATE_TOL`] an error — such a state is not a solution,
/// whatever the iteration's stopping rule said. Local (the certificates are reduced already).
fn check_certificates(
    kkt: &Kkt,
    friction: Option<&FrictionCertificate>,
    scales: &Scales,
    keys: &CaseKeys,
) -> Result<Option<Warning>, RunError> {
    // each certificate's worst violation relative to its scales
    let (kkt_worst, fric_worst) = (kkt.worst(), friction.map_or(0.0, |f| f.worst(scales)));
    let (which, worst) = if fric_worst > kkt_worst {
        ("(3.18)", fric_worst)
    } else {
        ("(3.14)", kkt_worst)
    };
    let failure = || {
        format!(
            "the final state is not a solution: it violates {} beyond {:e} of the problem's \
             scales (force {:.3e}, length {:.3e}): KKT {}{} — the problem is probably ill-posed \
             (a load that contact and friction cannot carry, or a mesh of several bodies that \
             Dirichlet data do not hold: {}) or the linear solves inexact ({})",
            if fric_worst > report::CERTIFICATE_TOL {
                "(3.18)"
            } else {
                "(3.14)"
            },
            report::CERTIFICATE_TOL,
            scales.force,
            scales.length,
            json(kkt),
            friction
                .map(|f| format!(", friction {}", json(f)))
                .unwrap_or_default(),
            keys.named(&["dirichlet", "neumann", ".obstacle", ".friction"]),
            keys.solver
        )
    };
    let warning = |limit: f64| {
        format!(
            "the final state violates {which} by {worst:.1e} of the problem's scales (the \
             certificate line has each measure), beyond round-off ({limit:e}): the linear \
             solves were inexact ({}); a tighter tolerance sharpens it",
            keys.solver
        )
    };
    judge(worst, failure, warning)
}

/// The final state's global equilibrium and force-controlled pairs' balances: beyond
/// [`warnings::CERTIFICATE_ROUND_OFF`] of their references a warning, beyond
/// [`report::CERTIFICATE_TOL`] an error. (3.14) and (3.18) can hold at nodes whose forces (3.28)
/// are wrong: the Tresca block of tests/cases/tresca with `newton.c = 1e12` ended at an
/// unbalanced tangential force of 2.7e-3 of the load, exit 0, while its slip rows' springs
/// were judged against c (`active_set::spring_floor` now judges them against the stiffness).
/// `c`: the complementarity parameter of (3.23) the solve ran with. Pure.
pub fn check_balance(
    cert: &certificate::Certificate,
    keys: &CaseKeys,
    c: f64,
) -> Result<Option<Warning>, RunError> {
    let (which, worst) = match cert.relative.force_balance {
        Some(f) if f > cert.relative.equilibrium => ("a force-controlled pair's balance", f),
        _ => ("the global equilibrium", cert.relative.equilibrium),
    };
    let failure = || {
        format!(
            "the final state is not a solution: {which} fails by {worst:.3e} of the forces \
             it sums (beyond {:e}; the certificate line has each term): the linear solves \
             were inexact ({}) or the regularisation newton.c too large for double precision \
             (c = {c:.3e})",
            report::CERTIFICATE_TOL,
            keys.solver,
        )
    };
    let warning = |limit: f64| {
        format!(
            "the final state's forces do not balance: {which} fails by {worst:.1e} of the \
             forces it sums (the certificate line has each term), beyond round-off ({limit:e}): \
             the linear solves were inexact ({}) or newton.c too large; a tighter tolerance or \
             the default c sharpens it",
            keys.solver
        )
    };
    judge(worst, failure, warning)
}

/// A final state's worst relative violation `worst` judged: beyond [`report::CERTIFICATE_TOL`]
/// not a solution (the error `failure()`), beyond [`warnings::CERTIFICATE_ROUND_OFF`] the
/// [`warnings::INEXACT_FINAL_STATE`] warning `warning(limit)`. Pure.
fn judge(
    worst: f64,
    failure: impl FnOnce() -> String,
    warning: impl FnOnce(f64) -> String,
) -> Result<Option<Warning>, RunError> {
    if worst > report::CERTIFICATE_TOL {
        return Err(RunError::Failed(failure()));
    }
    let limit = warnings::CERTIFICATE_ROUND_OFF;
    Ok((worst > limit).then(|| Warning {
        code: warnings::INEXACT_FINAL_STATE,
        message: warning(limit),
        key: None,
        pair: None,
        value: worst,
        threshold: limit,
        at: None,
        steps: Vec::new(),
    }))
}

/// Compact JSON of a certificate (sorted keys).
fn json<T: Serialize>(v: &T) -> String {
    serde_json::to_value(v).expect("plain data").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use certificate::{balance, pair_balance, sample, StopRule};

    /// A certificate whose every measure holds but the equilibrium (`residual` of a load of 1)
    /// and, with `pair`, a force-controlled pair that carries 1 + `pair` of |F| = 1.
    fn judged(residual: f64, pair: Option<f64>) -> Result<Option<Warning>, RunError> {
        let eq = balance(
            [0.0, -1.0, 0.0],
            [0.0, 1.0 - residual, 0.0],
            [0.0; 3],
            [1.0; 3],
            2,
        );
        let pairs = pair.map(|p| vec![pair_balance("contact".into(), 1.0, 1.0 + p)]);
        let cert = sample(StopRule::ActiveSet, false, eq, pairs);
        check_balance(&cert, &CaseKeys::default(), 2.5e3)
    }

    #[test]
    fn forces_that_do_not_balance_warn_beyond_round_off_and_fail_beyond_the_tolerance() {
        assert!(judged(1e-12, None).unwrap().is_none());
        let w = judged(1e-7, None).unwrap().expect("beyond 1e-8");
        assert_eq!(w.code, warnings::INEXACT_FINAL_STATE);
        assert!(w.message.contains("global equilibrium"), "{}", w.message);
        assert!((w.value - 1e-7).abs() < 1e-12, "{}", w.value);
        let Err(RunError::Failed(why)) = judged(1e-3, None) else {
            panic!("an equilibrium 1e-3 off is no solution");
        };
        assert!(
            why.contains("not a solution") && why.contains("c = 2.500e3"),
            "{why}"
        );
        // a force-controlled pair's balance is judged alike, and named
        let w = judged(0.0, Some(5e-8)).unwrap().expect("beyond 1e-8");
        assert!(w.message.contains("force-controlled pair"), "{}", w.message);
        assert!(matches!(judged(0.0, Some(1e-5)), Err(RunError::Failed(_))));
    }
}
