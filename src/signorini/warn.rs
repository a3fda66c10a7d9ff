//! The warnings of a converged contact solve (docs/warnings.md) that the body's geometry
//! reveals: a pressed obstacle that ends with no active node, and a contact force that pulls
//! the body's surface outward. Both compare the obstacle's normal n_k at a contact node with
//! the body's own outward normal o_k there (the facets of the contact group, oriented away
//! from their cells): a normal given the wrong way round makes them point the same way.
//! One pass over the contact facets and one gather of a few numbers per pair and rank.

use super::boundary::{ContactBoundary, NodeResult};
use crate::assembly::{facet_cell, outward_normal};
use crate::geom::dot;
use crate::mesh::Mesh;
use crate::par::Ctx;
use crate::partition::Layout;
use crate::setup::{group_facets, ContactSettings};
use crate::warnings::{self, Place, Warning};
use std::collections::HashMap;

/// A node is judged by the pressed test only where the obstacle's normal lies within 60° of
/// the line of the body's outward normal (|n·o| ≥ 1/2): elsewhere the two directions do not
/// say on which side of the surface the body is.
const FACING: f64 = 0.5;

/// A node counts as pressed through the obstacle's surface when it ends beyond it by more
/// than this fraction of the body's size (far above round-off, far below any real press).
const CROSSED_RTOL: f64 = 1e-9;

/// The unit outward normal of the body at every owned contact node (in the order of
/// `b.nodes`): the measure-weighted mean of its contact facets' outward normals; zero where
/// none is found. Local.
pub fn outward_normals(
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    b: &ContactBoundary,
) -> Vec<[f64; 3]> {
    let index: HashMap<usize, usize> = b
        .nodes
        .iter()
        .enumerate()
        .map(|(i, k)| (k.node, i))
        .collect();
    let mut out = vec![[0.0; 3]; b.nodes.len()];
    for pair in &settings.pairs {
        for f in group_facets(mesh, &pair.group) {
            let nodes = mesh.facet(f);
            if !nodes.iter().any(|v| index.contains_key(v)) {
                continue;
            }
            let Some((_, opp)) = facet_cell(mesh, layout, f) else {
                continue;
            };
            let (n, m) = outward_normal(mesh, f, opp);
            for v in nodes {
                if let Some(&i) = index.get(v) {
                    for c in 0..3 {
                        out[i][c] += m * n[c];
                    }
                }
            }
        }
    }
    for o in &mut out {
        let len = dot(*o, *o).sqrt();
        if len > 0.0 {
            o.iter_mut().for_each(|x| *x /= len);
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
    (mesh, layout, settings): (&Mesh, &Layout, &ContactSettings),
    b: &ContactBoundary,
    res: &[NodeResult],
    displacement: &[[f64; 3]],
) -> Vec<Warning> {
    let dim = mesh.dim;
    let size = mesh.extent();
    let outward = outward_normals(mesh, layout, settings, b);
    let np = settings.pairs.len();
    // per pair: [active, crossed h, its tag, x(3), pull, push, active with a pull, largest
    // pull, its tag, x(3)]
    let mut local = vec![0.0; REC * np];
    for r in local.chunks_exact_mut(REC) {
        r[1] = f64::NEG_INFINITY;
        r[9] = f64::NEG_INFINITY;
    }
    for ((k, r), o) in b.nodes.iter().zip(res).zip(&outward) {
        let rec = &mut local[REC * k.pair..REC * (k.pair + 1)];
        let along = dot(k.frame.n, *o);
        if r.active {
            rec[0] += 1.0;
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
    let all = ctx.all_gather_varcount(&local);
    let mut list = Vec::new();
    for (p, pair) in settings.pairs.iter().enumerate() {
        let mut t = [0.0; REC];
        t[1] = f64::NEG_INFINITY;
        t[9] = f64::NEG_INFINITY;
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
    list
}
