//! The warnings of a converged contact solve (docs/warnings.md) that the body's geometry
//! reveals: a pressed obstacle that ends with no active node, and a contact force that pulls
//! the body's surface outward. Both compare the obstacle's normal n_k at a contact node with
//! the body's own outward normal o_k there (the facets of the contact group, oriented away
//! from their cells): a normal given the wrong way round makes them point the same way.
//! One pass over the contact facets and one gather of a few numbers per pair and rank.

use super::boundary::{ContactBoundary, ContactNode, NodeResult};
use super::plain_path::ContactProblem;
use crate::assembly::{facet_cell, outward_normal};
use crate::geom::dot;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::setup::{group_facets, ContactSettings, PairSettings};
use crate::warnings::{self, Place, Warning};
use std::collections::HashMap;

/// A node is judged by the pressed test only where the obstacle's normal lies within 60° of
/// the line of the body's outward normal (|n·o| ≥ 1/2): elsewhere the two directions do not
/// say on which side of the surface the body is.
pub const FACING: f64 = 0.5;

/// A node counts as pressed through the obstacle's surface when it ends beyond it by more
/// than this fraction of the body's size (far above round-off, far below any real press).
pub const CROSSED_RTOL: f64 = 1e-9;

/// The unit outward normal of the body at every owned contact node (in the order of
/// `nodes`): the measure-weighted mean of its contact facets' outward normals; zero where
/// none is found. Local.
pub fn outward_normals(
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    nodes: &[ContactNode],
) -> Vec<[f64; 3]> {
    let facets = (settings.pairs.iter()).flat_map(|pair| group_facets(mesh, &pair.group));
    let summed = summed_normals(mesh, layout, facets);
    nodes
        .iter()
        .map(|k| {
            let o = summed[k.node];
            let len = dot(o, o).sqrt();
            if len > 0.0 {
                o.map(|x| x / len)
            } else {
                o
            }
        })
        .collect()
}

/// At every local node, the sum of the measure-weighted outward normals of those of `facets`
/// it belongs to (zero off them; not normalised). Local.
fn summed_normals(
    mesh: &Mesh,
    layout: &Layout,
    facets: impl IntoIterator<Item = usize>,
) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; mesh.n_nodes()];
    for f in facets {
        let Some((_, opp)) = facet_cell(mesh, layout, f) else {
            continue;
        };
        let (n, m) = outward_normal(mesh, f, opp);
        for &v in mesh.facet(f) {
            for c in 0..3 {
                out[v][c] += m * n[c];
            }
        }
    }
    out
}

/// One pair's numbers on one rank (gathered, then combined in rank order on every rank).
const REC: usize = 14;

/// The contact warnings of a converged solve: per pair, a pressed obstacle without an active
/// node ([`warnings::PRESSED_WITHOUT_CONTACT`]) and a pulling contact force
/// ([`warnings::PULLING_FORCE`]). `displacement`: each pair's obstacle displacement d in the
/// solve (the gaps of `b` are g0 − d·n). Collective (one gather); the same list on every rank.
pub fn contact_warnings(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    b: &ContactBoundary,
    res: &[NodeResult],
    displacement: &[[f64; 3]],
) -> Vec<Warning> {
    let outward = outward_normals(mesh, layout, settings, &b.nodes);
    let np = settings.pairs.len();
    let local = local_records(b, res, &outward, displacement, np);
    let all = ctx.all_gather_varcount(&local);
    let mut list = Vec::new();
    for (p, pair) in settings.pairs.iter().enumerate() {
        let t = combined(&all, p, np);
        pair_warnings(pair, &t, mesh.dim, mesh.extent(), &mut list);
    }
    list
}

/// The warnings the solution's geometry raises ([`contact_warnings`], [`through_obstacles`])
/// on `problem`'s judged boundary, with the solution's contact nodes and u's owned rows
/// `solution`; a vanishing step (`vanishing`) raises no pulling force: its forces, and their
/// signs, are round-off (a stack with Coulomb taken back to no load warned of a pull of 62 %
/// among forces of 1e-29, tests/load_steps.rs). Collective.
pub fn solution_warnings(
    ctx: &Ctx,
    problem: &ContactProblem,
    settings: &ContactSettings,
    (nodes, u): (&[NodeResult], &[f64]),
    displacement: &[[f64; 3]],
    vanishing: bool,
) -> Vec<Warning> {
    let (mesh, layout, b) = (problem.mesh, problem.layout, problem.boundary);
    let mut list = contact_warnings(ctx, mesh, layout, settings, b, nodes, displacement);
    if vanishing {
        list.retain(|w| w.code != warnings::PULLING_FORCE);
    }
    list.extend(through_obstacles(
        ctx,
        mesh,
        layout,
        settings,
        b,
        u,
        displacement,
        problem.fixed,
    ));
    list
}

/// An empty record: sums 0, the largest values −∞.
fn empty_record() -> [f64; REC] {
    let mut r = [0.0; REC];
    r[1] = f64::NEG_INFINITY;
    r[9] = f64::NEG_INFINITY;
    r
}

/// This rank's records, `REC` numbers per pair: [active, crossed h, its tag, x(3), pull, push,
/// active with a pull, largest pull, its tag, x(3)]. Local.
fn local_records(
    b: &ContactBoundary,
    res: &[NodeResult],
    outward: &[[f64; 3]],
    displacement: &[[f64; 3]],
    np: usize,
) -> Vec<f64> {
    let mut local: Vec<f64> = (0..np).flat_map(|_| empty_record()).collect();
    for ((k, r), o) in b.nodes.iter().zip(res).zip(outward) {
        let rec = &mut local[REC * k.pair..REC * (k.pair + 1)];
        let along = dot(k.frame.n, *o);
        if r.active {
            rec[0] += 1.0;
        }
        // judged where the obstacle faces the body's surface (|n·o| ≥ 1/2), as the pressed
        // warning judges: where its normal lies along the surface (a corner node of a side
        // group on a plane that the side stands on) the force's part along o is round-off, and
        // its sign — which changed with the rank count and the path — decided the warning
        if r.active && along.abs() >= FACING {
            // the contact force on the body, −λ, along the body's outward normal
            let f_out = -dot(r.lambda, *o);
            rec[6] += f_out.max(0.0);
            rec[7] += (-f_out).max(0.0);
            if f_out > 0.0 {
                rec[8] += 1.0;
                if f_out > rec[9] || (f_out == rec[9] && (k.tag as f64) < rec[10]) {
                    rec[9] = f_out;
                    rec[10] = k.tag as f64;
                    rec[11..14].copy_from_slice(&k.x);
                }
            }
        }
        if along.abs() < FACING {
            continue;
        }
        // s = +1: the obstacle's normal points out of the body (the wrong way round)
        let s = along.signum();
        let g0 = k.gap + dot(displacement[k.pair], k.frame.n);
        // beyond the obstacle's surface on the side the body faces: before, and at the end
        let h = s * (k.gap + r.u_n);
        if s * g0 <= 0.0 && (h > rec[1] || (h == rec[1] && (k.tag as f64) < rec[2])) {
            rec[1] = h;
            rec[2] = k.tag as f64;
            rec[3..6].copy_from_slice(&k.x);
        }
    }
    local
}

/// Pair `p`'s record over every rank's (`all`: the ranks' records in rank order, `np` pairs
/// each): sums added, the largest values kept with their node (ties: the smaller tag). Local.
fn combined(all: &[f64], p: usize, np: usize) -> [f64; REC] {
    let mut t = empty_record();
    for r in all
        .chunks_exact(REC * np)
        .map(|r| &r[REC * p..REC * (p + 1)])
    {
        for i in [0, 6, 7, 8] {
            t[i] += r[i];
        }
        for (v, rest) in [(1, 2..6), (9, 10..14)] {
            if r[v] > t[v] || (r[v] == t[v] && r[rest.start] < t[rest.start]) {
                t[v] = r[v];
                t[rest.clone()].copy_from_slice(&r[rest]);
            }
        }
    }
    t
}

/// The warnings of one pair's combined record `t` (`size`: the body's extent), pushed on
/// `list`. Local.
fn pair_warnings(
    pair: &crate::setup::PairSettings,
    t: &[f64; REC],
    dim: usize,
    size: f64,
    list: &mut Vec<Warning>,
) {
    let obstacle = pair.key("obstacle");
    let warning = |code, message: String, value, threshold, tag: f64, x: &[f64]| Warning {
        code,
        message,
        key: Some(obstacle.clone()),
        pair: Some(pair.key.clone()),
        value,
        threshold,
        at: Some(Place {
            node: Some(tag as u64),
            cell: None,
            x: x[..dim].to_vec(),
        }),
        steps: Vec::new(),
    };
    if t[0] == 0.0 && t[1] > CROSSED_RTOL * size {
        let msg = format!(
            "{}: the obstacle is pressed into the body, yet no contact node is active (total \
             force 0): contact node {} at {} ends {:.4e} beyond the obstacle's surface, on \
             the side the body faces, without touching it — does the obstacle's normal point \
             from the obstacle into the body, and do its motion or force and the loads point \
             the way intended? (key '{obstacle}')",
            pair.key,
            t[2] as u64,
            warnings::coords(&t[3..3 + dim]),
            t[1]
        );
        list.push(warning(
            warnings::PRESSED_WITHOUT_CONTACT,
            msg,
            t[1] / size,
            CROSSED_RTOL,
            t[2],
            &t[3..6],
        ));
    }
    let normal = t[6] + t[7];
    if t[6] > 0.0 && t[6] > warnings::PULL_FRACTION * normal {
        let msg = format!(
            "{}: the contact force pulls the body's surface outward at {} of its {} active \
             node(s), {:.1} % of the normal contact force (the most at contact node {} at \
             {}): contact can only push — does the obstacle's normal point from the \
             obstacle into the body? (key '{obstacle}')",
            pair.key,
            t[8] as usize,
            t[0] as usize,
            100.0 * t[6] / normal,
            t[10] as u64,
            warnings::coords(&t[11..11 + dim])
        );
        list.push(warning(
            warnings::PULLING_FORCE,
            msg,
            t[6] / normal,
            warnings::PULL_FRACTION,
            t[10],
            &t[11..14],
        ));
    }
}

/// One pair's record of [`through_obstacles`]: [count, deepest, its tag, x(3), Dirichlet].
const THROUGH: usize = 7;

/// [`warnings::THROUGH_OBSTACLE`]: per pair with a rigid obstacle, the nodes of the mesh's
/// boundary elements (its facet groups) that are not that pair's contact nodes — outside its
/// group, or in it but left to their Dirichlet data —, whose surface faces the obstacle (the
/// body's outward normal o there against the obstacle's n: n·o ≤ −1/2), that start on the body's side of
/// the obstacle (g0 ≥ −[`CROSSED_RTOL`] × size) but end beyond its surface by more than
/// [`CROSSED_RTOL`] × size (first-order gaps, g0 − d·n + u·n, as the contact nodes'; a node
/// that its Dirichlet data hold along n by g0 + u·n, its own prescribed motion): the
/// obstacle holds only the group's nodes, and the rest of the body went through it unseen (a
/// block pressed down at its top with its side as the contact group ended with its bottom
/// 0.0118 inside the plane it stands on, at exit 0). Not for body pairs (their u is in the
/// mortar basis). `u`: the owned nodes' rows of u. Collective (one gather).
#[allow(clippy::too_many_arguments)]
pub fn through_obstacles(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    b: &ContactBoundary,
    u: &[f64],
    displacement: &[[f64; 3]],
    fixed: &[f64],
) -> Vec<Warning> {
    if (settings.pairs.iter()).any(|p| matches!(p.obstacle, crate::contact::Obstacle::Body(_))) {
        return Vec::new();
    }
    let solved = Solved {
        u,
        displacement,
        fixed,
    };
    let local = through_records(mesh, layout, settings, b, &solved);
    let all = ctx.all_gather_varcount(&local);
    let np = settings.pairs.len();
    (settings.pairs.iter().enumerate())
        .filter_map(|(p, pair)| {
            let mut t = [0.0; THROUGH];
            t[1] = f64::NEG_INFINITY;
            for r in all.chunks_exact(THROUGH * np) {
                let r = &r[THROUGH * p..THROUGH * (p + 1)];
                t[0] += r[0];
                if r[1] > t[1] || (r[1] == t[1] && r[2] < t[2]) {
                    t[1..].copy_from_slice(&r[1..]);
                }
            }
            through_warning(pair, &t, mesh.dim, mesh.extent())
        })
        .collect()
}

/// What [`through_obstacles`] judges a node by: u's owned rows, each pair's obstacle
/// displacement, the Dirichlet values (NaN: free).
struct Solved<'a> {
    u: &'a [f64],
    displacement: &'a [[f64; 3]],
    fixed: &'a [f64],
}

/// This rank's [`THROUGH`] records of [`through_obstacles`], one per pair: its owned nodes of
/// the boundary elements, each projected onto every pair's obstacle but its own. Local.
fn through_records(
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    b: &ContactBoundary,
    s: &Solved,
) -> Vec<f64> {
    let np = settings.pairs.len();
    let tol = CROSSED_RTOL * mesh.extent();
    let outward = summed_normals(mesh, layout, 0..mesh.n_facets());
    let pair_of: HashMap<usize, usize> = b.nodes.iter().map(|k| (k.node, k.pair)).collect();
    let mut local = vec![0.0; THROUGH * np];
    for r in local.chunks_exact_mut(THROUGH) {
        r[1] = f64::NEG_INFINITY;
    }
    for (i, &v) in layout.owned_nodes.iter().enumerate() {
        if outward[v] == [0.0; 3] {
            continue; // on no boundary element
        }
        for (p, pair) in settings.pairs.iter().enumerate() {
            if pair_of.get(&v) == Some(&p) {
                continue;
            }
            let Some((depth, held)) = depth_beyond(mesh, pair, p, (i, v), outward[v], s) else {
                continue;
            };
            let rec = &mut local[THROUGH * p..THROUGH * (p + 1)];
            let tag = mesh.node_tags[v] as f64;
            if depth > tol {
                rec[0] += 1.0;
                if depth > rec[1] || (depth == rec[1] && tag < rec[2]) {
                    rec[1] = depth;
                    rec[2] = tag;
                    rec[3..6].copy_from_slice(&mesh.coords[v]);
                    rec[6] = if held { 1.0 } else { 0.0 };
                }
            }
        }
    }
    local
}

/// How far the node `v` (owned index `i`, the summed outward normal `o` of its boundary
/// elements) ends beyond pair `p`'s obstacle (first-order, g0 − d·n + u·n; by g0 + u·n where
/// its Dirichlet data hold it along n), and whether they do; `None` where it is not judged:
/// not projectable, started inside (the start's own warning, or the case's intent), or on a
/// surface that does not face the obstacle (a block squashed beyond its own height by a load
/// of 5 × E moves its top below the plane it stands on: large_deformation's). Local.
fn depth_beyond(
    mesh: &Mesh,
    pair: &PairSettings,
    p: usize,
    (i, v): (usize, usize),
    o: [f64; 3],
    s: &Solved,
) -> Option<(f64, bool)> {
    let dim = mesh.dim;
    let proj = pair.obstacle.project(mesh.coords[v]).ok()?;
    let n = proj.normal;
    let tol = CROSSED_RTOL * mesh.extent();
    if proj.gap < -tol || dot(n, o) > -FACING * dot(o, o).sqrt() {
        return None;
    }
    let un: f64 = (0..dim).map(|c| s.u[i * dim + c] * n[c]).sum();
    // held along n: judged by its own prescribed motion alone, not by the obstacle's (a plate
    // pressed onto a block whose corners are clamped passes the clamped corners as intended)
    let free2: f64 = (0..dim)
        .filter(|&c| s.fixed[v * dim + c].is_nan())
        .map(|c| n[c] * n[c])
        .sum();
    let held = free2 < FACING * FACING;
    let moved = if held { 0.0 } else { dot(s.displacement[p], n) };
    Some((-(proj.gap - moved + un), held))
}

/// The warning of one pair's combined record `t` of [`through_obstacles`] (`size`: the body's
/// extent); `None` where no node went through. Pure.
fn through_warning(
    pair: &PairSettings,
    t: &[f64; THROUGH],
    dim: usize,
    size: f64,
) -> Option<Warning> {
    if t[0] == 0.0 {
        return None;
    }
    let group = pair.key("group");
    let why = if t[6] > 0.0 {
        "held by Dirichlet data that move it there"
    } else {
        "in no contact group of this pair"
    };
    let message = format!(
        "{}: {} boundary node(s) that are not its contact nodes end beyond its obstacle's \
         surface, up to {:.4e} (node {} at {}, {why}): the obstacle holds only the nodes of \
         its contact group, and the rest of the body went through it unseen — should the \
         group (key '{group}') hold them, or the Dirichlet data let them go?",
        pair.key,
        t[0] as u64,
        t[1],
        t[2] as u64,
        warnings::coords(&t[3..3 + dim])
    );
    Some(Warning {
        code: warnings::THROUGH_OBSTACLE,
        message,
        key: Some(group),
        pair: Some(pair.key.clone()),
        value: t[1] / size,
        threshold: CROSSED_RTOL,
        at: Some(Place {
            node: Some(t[2] as u64),
            cell: None,
            x: t[3..3 + dim].to_vec(),
        }),
        steps: Vec::new(),
    })
}

/// The warnings of a pair's start ([`warnings::START_INSIDE`]), from the gaps g0 of `nodes`
/// (before any motion): contact nodes that start on the obstacle's far side — inside it where
/// its normal points out of the body (n·o ≥ 1/2), by more than [`CROSSED_RTOL`] of the body's
/// size —, or inside it by more than [`warnings::START_INSIDE_FRACTION`] of the body's size
/// wherever they are (an indenter placed into the body by a small overlap is the usual way to
/// prescribe its depth: no warning). Collective (one gather); the same on every rank.
pub fn start_warnings(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    nodes: &[ContactNode],
) -> Vec<Warning> {
    let dim = mesh.dim;
    let size = mesh.extent();
    let outward = outward_normals(mesh, layout, settings, nodes);
    let np = settings.pairs.len();
    let all = ctx.all_gather_varcount(&local_starts(nodes, &outward, np));
    settings
        .pairs
        .iter()
        .enumerate()
        .filter_map(|(p, pair)| start_warning(pair, &pair_starts(&all, p, np), size, dim))
        .collect()
}

/// The length of a pair's record of its start: per kind (far side, any) the deepest node's
/// [depth, tag, x(3)], then [inside, nodes].
const START: usize = 12;

/// This rank's records of the pairs' starts (`np` pairs; `outward`: the body's outward normal
/// at each node): per kind the deepest node (the lowest tag among equals), the nodes inside
/// and the nodes. Local.
fn local_starts(nodes: &[ContactNode], outward: &[[f64; 3]], np: usize) -> Vec<f64> {
    let mut local = vec![0.0; START * np];
    for r in local.chunks_exact_mut(START) {
        r[0] = f64::NEG_INFINITY;
        r[5] = f64::NEG_INFINITY;
    }
    for (k, o) in nodes.iter().zip(outward) {
        let rec = &mut local[START * k.pair..START * (k.pair + 1)];
        rec[11] += 1.0;
        if k.gap >= 0.0 {
            continue;
        }
        rec[10] += 1.0;
        let far = dot(k.frame.n, *o) >= FACING;
        for (base, judged) in [(0, far), (5, true)] {
            let depth = -k.gap;
            let r = &mut rec[base..base + 5];
            if judged && (depth > r[0] || (depth == r[0] && (k.tag as f64) < r[1])) {
                r[0] = depth;
                r[1] = k.tag as f64;
                r[2..5].copy_from_slice(&k.x);
            }
        }
    }
    local
}

/// Pair `p`'s start record over every rank (`all`: the ranks' [`local_starts`] of `np` pairs).
fn pair_starts(all: &[f64], p: usize, np: usize) -> [f64; START] {
    let mut t = [0.0; START];
    t[0] = f64::NEG_INFINITY;
    t[5] = f64::NEG_INFINITY;
    for r in all
        .chunks_exact(START * np)
        .map(|r| &r[START * p..START * (p + 1)])
    {
        t[10] += r[10];
        t[11] += r[11];
        for b in [0, 5] {
            if r[b] > t[b] || (r[b] == t[b] && r[b + 1] < t[b + 1]) {
                t[b..b + 5].copy_from_slice(&r[b..b + 5]);
            }
        }
    }
    t
}

/// The warning of a pair's start record `t` ([`pair_starts`]; `size`: the body's), if any.
fn start_warning(pair: &PairSettings, t: &[f64; START], size: f64, dim: usize) -> Option<Warning> {
    let (inside, total) = (t[10] as usize, t[11] as usize);
    let (base, threshold, why) = if t[0] > CROSSED_RTOL * size {
        (
            0,
            CROSSED_RTOL,
            "on the obstacle's far side: inside it where its normal points out of the body \
             — does the normal point from the obstacle into the body, and is the obstacle \
             on the body's side?",
        )
    } else if t[5] > warnings::START_INSIDE_FRACTION * size {
        (
            5,
            warnings::START_INSIDE_FRACTION,
            "deeper than a small overlap — is the obstacle placed where it should be \
             (units, origin, the sign of a coordinate)?",
        )
    } else {
        return None;
    };
    let (depth, tag, x) = (
        t[base],
        t[base + 1] as u64,
        t[base + 2..base + 2 + dim].to_vec(),
    );
    Some(Warning {
        code: warnings::START_INSIDE,
        message: format!(
            "{}: the body starts {depth:.4e} inside the obstacle ({:.2} % of the body's size \
             {size:.4e}; contact node {tag} at {}; {inside} of {total} contact nodes inside), \
             {why} (key '{}')",
            pair.key,
            100.0 * depth / size,
            warnings::coords(&x),
            pair.key("obstacle")
        ),
        key: Some(pair.key("obstacle")),
        pair: Some(pair.key.clone()),
        value: depth / size,
        threshold,
        at: Some(Place {
            node: Some(tag),
            cell: None,
            x,
        }),
        steps: Vec::new(),
    })
}
