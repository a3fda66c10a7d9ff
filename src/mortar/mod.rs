//! Contact between deformable bodies by dual mortar (docs/bodies.md).
//!
//! A pair whose obstacle is another body (`type = "body"`) holds its (slave) nodes against
//! the other body's (master) boundary group. The mortar integrals of
//! [`crate::contact::mortar`] give each covered slave node k the weight D_kk, the master
//! couplings M_kj and the weighted gap g̃_k; with m_kj = M_kj / D_kk the condition is
//! n_k·(u_k − Σ_j m_kj u_j) + g̃_k / D_kk ≥ 0 (Hüeber & Wohlmuth, CMAME 194, 2005).
//!
//! The contact algorithm takes these rows by a change of basis ([`Basis`]): the slave node's
//! unknowns become its displacement relative to the master side it faces,
//! w_k = u_k − Σ_j m_kj u_j, every other unknown stays (w_j = u_j); u = Q w + c, c the part
//! of Q's couplings on Dirichlet-fixed master components. In w the condition of node k reads
//! its own unknowns only, n_k·w_k + g_k ≥ 0, as against a rigid obstacle, so Algorithms 1 and
//! 2, their sets (3.23)/(3.33), the reduced systems (3.29)/(3.42), the Schur path and the
//! multiplier recovery (3.28) apply unchanged to Qᵀ A Q w = Qᵀ (f − A c): the multiplier of a
//! slave row is the contact force on its node, and the master rows receive −m_kj times it
//! through Qᵀ. The change of basis is the contact constraint operator: a new kind of
//! contact row is a new Q.
//!
//! With a friction law a slave node's frame is the common normal of the two surfaces where
//! they face each other ([`MasterNormals`]), not the slave's own: the approach of two curved
//! bodies then has no tangential part that a sticking node would resist.
//!
//! Set-up (collective, once per run): each rank sends the master facets it is first to own
//! (a facet goes out from the owner of its smallest-numbered node) to the ranks whose slave
//! facets' bounding box (widened by the reach) they meet; each rank integrates its own slave
//! facets and keeps the rows of its owned slave nodes.

mod basis;
mod exchange;

pub use basis::{Basis, InU};

use crate::contact::mortar::{
    assemble_with_normals, MortarOptions, MortarRow, Orientation, Surface,
};
use crate::contact::obstacle::{BodyTarget, Obstacle, SlaveRow};
use crate::error::{InputError, RunError};
use crate::mesh::{BodyModes, Mesh, Part, NO_SLOT};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::setup::ContactSettings;
use exchange::{MasterFacets, Reach, SlaveFacets};
use std::collections::HashMap;
use std::sync::Arc;

/// The Dirichlet-fixed components of the master nodes this rank couples to, by global node.
pub(crate) type MasterFixed = HashMap<usize, [bool; 3]>;

/// Each body pair's slave rows by mesh node: (pair index, rows).
pub(crate) type PairRows = (usize, HashMap<usize, SlaveRow>);

/// Sets up every body pair of `settings` (their slave rows into the pairs' [`BodyTarget`])
/// and returns the change of basis; `None` without body pairs. Input errors (exit 2) name
/// the pair's keys. Collective.
pub fn set_up(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &mut ContactSettings,
    fixed: &[f64],
) -> Result<Option<Basis>, RunError> {
    let body_pairs: Vec<usize> = (settings.pairs.iter().enumerate())
        .filter(|(_, p)| matches!(p.obstacle, Obstacle::Body(_)))
        .map(|(i, _)| i)
        .collect();
    if body_pairs.is_empty() {
        return Ok(None);
    }
    ctx.agree(check_pairs(mesh, settings, &body_pairs).map_err(RunError::Input))?;
    let slaves: Vec<(usize, SlaveFacets)> = (body_pairs.iter())
        .map(|&p| (p, SlaveFacets::of(mesh, layout, &settings.pairs[p].group)))
        .collect();
    let reach = Reach::of(ctx, settings.pairs.len(), &slaves);
    let masters = MasterFacets::exchange(ctx, mesh, layout, settings, fixed, &reach);
    check_overlap(ctx, mesh, layout, settings, &slaves)?;
    let mut master_fixed = MasterFixed::new();
    let mut rows_of = Vec::new();
    for (p, slave) in &slaves {
        let p = *p;
        let rows = ctx.agree(
            pair_rows(
                mesh,
                layout,
                settings,
                PairSides {
                    p,
                    own: slave,
                    masters: &masters,
                    radius: reach.radius[p],
                },
                fixed,
            )
            .map_err(RunError::Input),
        )?;
        check_through(ctx, mesh, layout, settings, p, &rows)?;
        let facing = ctx.sum_usize(rows.len());
        let rows = keep_contact_nodes(mesh, rows, fixed);
        let covered = ctx.sum_usize(rows.len());
        if covered == 0 && facing > 0 {
            let pair = &settings.pairs[p];
            return Err(RunError::Input(
                InputError::new(
                    &settings.file,
                    format!(
                        "the {facing} node(s) of the group \"{}\" that face the group \"{}\" \
                         are all held along the contact normal by Dirichlet data: no slave \
                         node is left to the contact; free the slave group's normal \
                         component, or make \"{}\" the slave side",
                        pair.group,
                        master_group(&pair.obstacle),
                        master_group(&pair.obstacle),
                    ),
                )
                .with_key(pair.key("group")),
            ));
        }
        if covered == 0 {
            let pair = &settings.pairs[p];
            return Err(RunError::Input(
                InputError::new(
                    &settings.file,
                    format!(
                        "no node of the group \"{}\" faces the group \"{}\" within {:.3e} (the \
                         size of the slave group): the two groups of a body pair must face \
                         each other",
                        pair.group,
                        master_group(&pair.obstacle),
                        reach.radius[p]
                    ),
                )
                .with_key(pair.key("obstacle.group")),
            ));
        }
        masters.fixed_of(p, &mut master_fixed);
        if let Some(modes) = settings.modes.as_mut() {
            let faces = master_sides(&rows, &masters.nodes_of(p));
            let modes = Arc::make_mut(modes);
            for (v, parts) in faces {
                modes.set_faces(v, parts);
            }
        }
        rows_of.push((p, rows));
    }
    let basis = Basis::new(ctx, mesh, layout, &rows_of, &master_fixed, fixed)?;
    for (p, rows) in rows_of {
        let Obstacle::Body(t) = &mut settings.pairs[p].obstacle else {
            unreachable!("a body pair")
        };
        let mut target = BodyTarget::clone(t);
        target.rows = rows;
        *t = Arc::new(target);
    }
    Ok(Some(basis))
}

/// Per slave row (mesh node): the master side it faces, per body with rigid modes
/// ([`crate::mesh::Part`]: Σ_j m_kj and Σ_j m_kj x_j over that body's master nodes), from
/// `nodes` (master node → slot, coordinates). Local.
fn master_sides(
    rows: &HashMap<usize, SlaveRow>,
    nodes: &HashMap<usize, (u32, [f64; 3])>,
) -> Vec<(usize, Vec<Part>)> {
    let mut out = Vec::new();
    for (&v, r) in rows {
        let mut parts: Vec<Part> = Vec::new();
        for &(j, m) in &r.masters {
            let Some(&(slot, x)) = nodes.get(&j) else {
                continue;
            };
            if slot == NO_SLOT {
                continue;
            }
            let i = match parts.iter().position(|p| p.slot == slot) {
                Some(i) => i,
                None => {
                    parts.push(Part {
                        slot,
                        weight: 0.0,
                        moment: [0.0; 3],
                    });
                    parts.len() - 1
                }
            };
            parts[i].weight += m;
            for d in 0..3 {
                parts[i].moment[d] += m * x[d];
            }
        }
        out.push((v, parts));
    }
    out
}

/// The master group of a body pair.
fn master_group(o: &Obstacle) -> &str {
    match o {
        Obstacle::Body(t) => &t.group,
        _ => "",
    }
}

/// Each body pair's master group exists as a boundary group and differs from its slave
/// group. Local (the groups are known on every rank).
fn check_pairs(mesh: &Mesh, settings: &ContactSettings, pairs: &[usize]) -> Result<(), InputError> {
    for &p in pairs {
        let pair = &settings.pairs[p];
        let master = master_group(&pair.obstacle);
        let key = pair.key("obstacle.group");
        let found = mesh
            .groups
            .iter()
            .any(|g| g.name == master && g.dim + 1 == mesh.dim);
        if !found {
            return Err(InputError::new(
                &settings.file,
                format!(
                    "the mesh has no boundary group \"{master}\" (of dimension {}); its groups: \
                     {}",
                    mesh.dim - 1,
                    mesh.group_names().join(", ")
                ),
            )
            .with_key(key));
        }
        if pair.motion.is_some() || pair.force.is_some() {
            let which = if pair.motion.is_some() {
                "motion"
            } else {
                "force"
            };
            return Err(InputError::new(
                &settings.file,
                "a body pair has no motion or force of its own: move a body by its Dirichlet \
                 data or its loads",
            )
            .with_key(pair.key(which)));
        }
        if master == pair.group {
            return Err(InputError::new(
                &settings.file,
                format!(
                    "the pair's group \"{master}\" is also its obstacle's group: a body pair \
                     joins two different boundary groups"
                ),
            )
            .with_key(key));
        }
    }
    Ok(())
}

/// One body pair's two sides as this rank holds them: pair `p`, its owned slave facets, the
/// master facets received and the search radius of the pair's reach.
struct PairSides<'a> {
    p: usize,
    own: &'a SlaveFacets,
    masters: &'a MasterFacets,
    radius: f64,
}

/// The slave rows of pair `sides.p` for this rank's owned slave nodes the master covers.
/// Local.
fn pair_rows(
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    sides: PairSides,
    fixed: &[f64],
) -> Result<HashMap<usize, SlaveRow>, InputError> {
    let PairSides {
        p,
        own,
        masters,
        radius,
    } = sides;
    let pair = &settings.pairs[p];
    let dim = mesh.dim;
    let bad = |what: String| InputError::new(&settings.file, what).with_key(pair.key("group"));
    if own.facets.is_empty() {
        return Ok(HashMap::new());
    }
    let slave = Surface::new(dim, &own.facets, Orientation::InsidePoints(&own.inside))
        .map_err(|e| bad(format!("the slave group \"{}\": {e}", pair.group)))?;
    let Some(master) = masters.surface(p, dim).map_err(|e| {
        bad(format!(
            "the master group \"{}\": {e}",
            master_group(&pair.obstacle)
        ))
    })?
    else {
        return Ok(HashMap::new());
    };
    let opts = MortarOptions {
        search_radius: radius,
        max_normal_dot: Some(0.0),
    };
    let normals = symmetry_normals(&slave, fixed, dim);
    let mortar = assemble_with_normals(&slave, &master, &normals, &opts)
        .map_err(|e| bad(format!("mortar integrals: {e}")))?;
    let facing = settings.friction().then(|| {
        let mut held = MasterFixed::new();
        masters.fixed_of(p, &mut held);
        MasterNormals::of(&master, &held)
    });
    let mut rows = HashMap::new();
    for r in mortar.rows {
        if !layout.owns_node(r.id) || r.d <= 0.0 {
            continue;
        }
        let fx = &fixed[r.id * dim..(r.id + 1) * dim];
        let (normal, gap) = match &facing {
            Some(f) => f.common_normal(&r, fx),
            None => (r.normal, r.gap),
        };
        rows.insert(
            r.id,
            SlaveRow {
                normal: [-normal[0], -normal[1], -normal[2]],
                gap: gap / r.d,
                weight: r.d,
                masters: r.m.iter().map(|&(j, m)| (j, m / r.d)).collect(),
            },
        );
    }
    Ok(rows)
}

/// The master surface's outward nodal normals and coordinates, by mesh node.
struct MasterNormals(HashMap<usize, ([f64; 3], [f64; 3])>);

impl MasterNormals {
    /// The nodal normals of `master`, those of nodes with Dirichlet-fixed components (`held`)
    /// turned into the plane of their free ones as the slave's are ([`symmetry_normals`]):
    /// on a mirror plane the master's facets lie on one side, and its normal there is the
    /// mirrored surface's.
    fn of(master: &Surface, held: &MasterFixed) -> MasterNormals {
        let normals = master.nodal_normals();
        MasterNormals(
            (master.ids().iter().zip(normals).zip(master.coords()))
                .map(|((&j, mut n), &x)| {
                    if let Some(f) = held.get(&j) {
                        n = in_free_plane(n, f);
                    }
                    (j, (n, x))
                })
                .collect(),
        )
    }

    /// With friction, the frame of slave node k is the common normal of the two surfaces,
    /// n̄_k ∝ n_k − Σ_j m_kj n_j (n_j the master's outward nodal normals, m_kj = M_kj / D_kk),
    /// and the weighted gap along it g̃_k = n̄_k · (Σ_j M_kj x_j − D_kk x_k): the slave normal
    /// alone turns by x/R along a curved surface, and the approach of two curved bodies (along
    /// their common normal) would have a tangential part in it that a sticking node resists
    /// (docs/bodies.md, "The method"). On a flat interface n̄_k = n_k. Returns (n̄_k, g̃_k),
    /// the row's own where the two normals cancel, and where the master covers the slave
    /// facets around k only in part (at the end of the master group): there Σ_j m_kj ≠ 1
    /// (M_kj integrates the dual ψ_k, which changes sign, over the covered part only, D_kk the
    /// positive φ_k), so Σ_j m_kj n_j is no mean of the master's normals and n̄_k no common
    /// normal — a slave node beside a ball's silhouette started 1.6 deep inside the ball
    /// along it (docs/bodies.md, "The method"). `fx`: the node's Dirichlet values per
    /// component (NaN = free); a prescribed component is taken out of n̄_k, as out of the
    /// slave normal ([`symmetry_normals`]): on a mirror plane the master's nodal normals lean
    /// out of it (their facets lie on one side), and the node stays a symmetry row.
    fn common_normal(&self, r: &MortarRow, fx: &[f64]) -> ([f64; 3], f64) {
        if !r.fully_covered {
            return (r.normal, r.gap);
        }
        let (mut n, mut v) = (r.normal, [0.0; 3]);
        for &(j, m) in &r.m {
            let (nj, xj) = self.0[&j];
            for d in 0..3 {
                n[d] -= m / r.d * nj[d];
                v[d] += m * xj[d];
            }
        }
        for (d, x) in fx.iter().enumerate() {
            if !x.is_nan() {
                n[d] = 0.0;
            }
        }
        let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
        if len <= 1e-3 {
            return (r.normal, r.gap);
        }
        let n = n.map(|x| x / len);
        let gap = (0..3).map(|d| n[d] * (v[d] - r.d * r.x[d])).sum();
        (n, gap)
    }
}

/// The slave nodal normals (averaged facet normals), those of nodes with Dirichlet-fixed
/// components turned into the plane of their free ones: a slave group that ends on a symmetry
/// plane has there the normal of the mirrored surface (in the plane), not its last facet's,
/// tilted by about h / (2R) on a curved surface, so the node stays a contact node (a symmetry
/// row, [`keep_contact_nodes`]). Local.
fn symmetry_normals(slave: &Surface, fixed: &[f64], dim: usize) -> Vec<[f64; 3]> {
    let mut normals = slave.nodal_normals();
    for (n, &v) in normals.iter_mut().zip(slave.ids()) {
        let fx = &fixed[v * dim..(v + 1) * dim];
        let mut held = [false; 3];
        for (d, x) in fx.iter().enumerate() {
            held[d] = !x.is_nan();
        }
        *n = in_free_plane(*n, &held);
    }
    normals
}

/// The unit normal `n` with its `held` components taken out; `n` itself where that leaves
/// less than half of it (a normal along its fixed components: such a slave node is left to
/// its Dirichlet data by [`keep_contact_nodes`]).
fn in_free_plane(n: [f64; 3], held: &[bool; 3]) -> [f64; 3] {
    if !held.iter().any(|&h| h) {
        return n;
    }
    let mut m = n;
    for (d, &h) in held.iter().enumerate() {
        if h {
            m[d] = 0.0;
        }
    }
    let len = m.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len > 0.5 {
        m.map(|x| x / len)
    } else {
        n
    }
}

/// The slave rows that become contact nodes: a node with a Dirichlet-fixed component is left
/// to its Dirichlet data unless every fixed component is orthogonal to its normal (a symmetry
/// row), with or without friction — the rule of rigid pairs (signorini::boundary).
fn keep_contact_nodes(
    mesh: &Mesh,
    mut rows: HashMap<usize, SlaveRow>,
    fixed: &[f64],
) -> HashMap<usize, SlaveRow> {
    let dim = mesh.dim;
    rows.retain(|&v, r| {
        let fx = &fixed[v * dim..(v + 1) * dim];
        fx.iter()
            .enumerate()
            .all(|(d, x)| x.is_nan() || r.normal[d].abs() <= 1e-12)
    });
    rows
}

/// The bodies (of the driver's body survey, `modes`) that the facets of boundary group `name`
/// touch, a flag per body, every rank's; `None` for `modes`: the whole mesh is one body.
/// Collective.
fn group_bodies(ctx: &Ctx, mesh: &Mesh, modes: Option<&BodyModes>, name: &str) -> Vec<bool> {
    let Some(modes) = modes else {
        return vec![true];
    };
    let mut flags = vec![0.0; modes.bodies()];
    for f in crate::setup::group_facets(mesh, name) {
        for &v in mesh.facet(f) {
            if let Some(x) = flags.get_mut(modes.body_of(v) as usize) {
                *x = 1.0;
            }
        }
    }
    ctx.sum_vec(&flags).iter().map(|&x| x > 0.0).collect()
}

/// A slave node whose master group lies on its own body and which faces that group through
/// the material — its gap below minus its mesh size (weight^(1/(d−1))), as the two faces of
/// a plate do — is refused: one body touches itself only across a gap, where its two groups
/// face each other from outside (a C-shaped body's arms). Such a pair was solved as if the
/// plate's thickness were a penetration: every node in contact, strains of 1.6, exit 0. The
/// error names the node of smallest Gmsh tag on every rank count. Collective.
fn check_through(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    p: usize,
    rows: &HashMap<usize, SlaveRow>,
) -> Result<(), RunError> {
    let pair = &settings.pairs[p];
    let modes = settings.modes.as_deref();
    let master = group_bodies(ctx, mesh, modes, master_group(&pair.obstacle));
    let own_body = |v: usize| modes.map_or(0, |m| m.body_of(v) as usize);
    let dim = mesh.dim;
    let mut worst: Option<(u64, usize, f64, f64)> = None;
    for (&v, r) in rows {
        if !layout.owns_node(v) || !master.get(own_body(v)).copied().unwrap_or(false) {
            continue;
        }
        let h = r.weight.powf(1.0 / (dim as f64 - 1.0));
        let tag = mesh.node_tags[v];
        if r.gap < -h && worst.is_none_or(|w| tag < w.0) {
            worst = Some((tag, v, r.gap, h));
        }
    }
    let Some((tag, v, gap, h)) = worst else {
        return ctx.agree_smallest(None);
    };
    let e = InputError::new(
        &settings.file,
        format!(
            "mesh node {tag} at {:?} of the slave group \"{}\" faces the master group \"{}\" \
             of its own body through the material (its gap {gap:.4e}, its mesh size {h:.4e}): \
             a body touches itself only where its two groups face each other across a gap",
            &mesh.coords[v][..dim],
            pair.group,
            master_group(&pair.obstacle),
        ),
    )
    .with_key(pair.key("obstacle.group"));
    ctx.agree_smallest(Some((tag, RunError::Input(e))))
}

/// No node is a slave node of one pair and a master node of another (or of its own): the
/// change of basis substitutes master unknowns into slave rows once, and one body does not
/// touch itself. Each rank looks at the nodes it owns, whose every boundary facet is local
/// (their cells are), in the groups themselves — not in the master facets it received, which
/// come within each pair's own reach only, so that a node shared with another pair's master
/// group went unseen on some rank counts. The error names the offending node of smallest Gmsh
/// tag on every rank count. Collective.
fn check_overlap(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    slaves: &[(usize, SlaveFacets)],
) -> Result<(), RunError> {
    // the owned nodes of every body pair's master group, with the first such pair
    let mut master_of: HashMap<usize, usize> = HashMap::new();
    for (q, pair) in settings.pairs.iter().enumerate() {
        let Obstacle::Body(t) = &pair.obstacle else {
            continue;
        };
        for f in crate::setup::group_facets(mesh, &t.group) {
            for &v in mesh.facet(f) {
                if layout.owns_node(v) {
                    master_of.entry(v).or_insert(q);
                }
            }
        }
    }
    // this rank's offending node of smallest tag: (tag, node, slave pair, master pair)
    let mut worst: Option<(u64, usize, usize, usize)> = None;
    for (p, own) in slaves {
        for &(v, _) in own.facets.iter().flatten() {
            let Some(&q) = master_of.get(&v) else {
                continue;
            };
            let tag = mesh.node_tags[v];
            if worst.is_none_or(|w| tag < w.0) {
                worst = Some((tag, v, *p, q));
            }
        }
    }
    let Some((tag, v, p, q)) = worst else {
        return ctx.agree_smallest(None);
    };
    let pair = &settings.pairs[q];
    let e = InputError::new(
        &settings.file,
        format!(
            "mesh node {} at {:?} is a node of the slave group \"{}\" and of the master group \
             \"{}\": a node is on one side of body contact only (split the groups so that they \
             share no node)",
            mesh.node_tags[v],
            &mesh.coords[v][..mesh.dim],
            settings.pairs[p].group,
            master_group(&pair.obstacle),
        ),
    )
    .with_key(pair.key("obstacle.group"));
    ctx.agree_smallest(Some((tag, RunError::Input(e))))
}
