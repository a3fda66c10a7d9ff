//! The discrete contact boundary c_h: for every owned contact node its frame {n, τ}, gap
//! g_h^k (3.3), lumped weight w_k = ∫_Γc φ_k ds and Tresca bound b_k = ∫_Γc g_R φ_k ds (3.18);
//! and the per-node result record (u, λ in the node's frame) of an iterate.

use crate::contact::{Frame, Obstacle};
use crate::error::{InputError, RunError};
use crate::fem;
use crate::geom::dot;
use crate::mesh::{BodyModes, Mesh};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::setup::{group_facets, ContactSettings};
use std::sync::Arc;

/// One owned contact node.
#[derive(Clone, Debug)]
pub struct ContactNode {
    /// Mesh node index.
    pub node: usize,
    /// The contact pair of the node (index into the case's pairs; 0 with one pair).
    pub pair: usize,
    /// Coulomb's friction coefficient μ of the node's pair (0 on a frictionless pair and
    /// without Coulomb friction).
    pub mu: f64,
    /// Gmsh node tag.
    pub tag: u64,
    /// Global index of the node's first dof (dofs row .. row + dim).
    pub row: usize,
    /// Index of the first dof within this rank's owned rows.
    pub local_row: usize,
    pub x: [f64; 3],
    pub frame: Frame,
    /// Initial normal gap g_h^k (3.3), ≥ 0 outside the obstacle; against a moving obstacle
    /// the gap to where it is in this step, g0 − d·n (docs/obstacles.md, "Moving obstacles").
    pub gap: f64,
    /// w_k = ∫_Γc φ_k ds.
    pub weight: f64,
    /// b_k = ∫_Γc g_R φ_k ds (0 without friction; with Coulomb the final μ(−λ_n^k), set for
    /// the report).
    pub bound: f64,
    /// u_τ of the previous load step (frame components, 2D padded): friction acts on the
    /// increment u_τ − u_ref (docs/friction.md, "Load steps"); 0 for a single static solve.
    /// A moving obstacle carries the reference along: + the tangential part of its
    /// displacement since then (d_τ in a single solve).
    pub u_t_ref: [f64; 2],
}

/// Per owned contact node: displacement and multiplier, in global components and in the
/// node's frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct NodeResult {
    pub u: [f64; 3],
    pub lambda: [f64; 3],
    pub u_n: f64,
    pub u_t: [f64; 2],
    pub lambda_n: f64,
    pub lambda_t: [f64; 2],
    /// In A_n in the solve that produced this iterate.
    pub active: bool,
    /// In A_τ (slip) in that solve (friction only).
    pub slip: bool,
}

/// The candidate contact boundary c_h: this rank's contact nodes, plus what every rank knows
/// about the whole boundary.
#[derive(Clone, Debug)]
pub struct ContactBoundary {
    pub nodes: Vec<ContactNode>,
    /// |c_h| over all ranks.
    pub n_global: usize,
    /// Global numbering of contact nodes for output: this rank's are offset .. offset + len.
    pub offset: usize,
    /// Mesh nodes on the contact boundary (all of them, every rank), incl. ones excluded
    /// because Dirichlet data fix them.
    pub on_contact_boundary: Vec<bool>,
    /// Contact nodes dropped because Dirichlet data fix one of their components (global count).
    pub excluded_dirichlet: usize,
    /// Each pair's obstacle as the case gives it (its motion is in the nodes' gaps and
    /// references).
    pub obstacles: Vec<Obstacle>,
    /// The case file and keys that the diagnoses of the solve name.
    pub keys: CaseKeys,
    /// The rigid modes of the bodies Dirichlet data leave free, in the unknowns of every local
    /// node (signorini/rigid.rs).
    pub modes: Arc<BodyModes>,
    /// The nodal stiffness E h_c^(d−2) of the contact boundary (the default c is
    /// [`DEFAULT_C_FACTOR`](crate::tuning::DEFAULT_C_FACTOR) times it), once the solve set it;
    /// 0 before.
    pub stiffness: f64,
}

/// The case file and the keys a failed solve names, so the user knows what to change.
#[derive(Clone, Debug, Default)]
pub struct CaseKeys {
    pub file: std::path::PathBuf,
    /// Each pair's table (`contact` or `contact[i]`).
    pub pairs: Vec<String>,
    /// The linear solver's keys the case sets (`solver.preset = "iterative"`, ...).
    pub solver: String,
}

impl CaseKeys {
    /// "FILE: keys 'a', 'b'" for the keys `names` (each pair's `KEY.name` for a name that
    /// starts with '.').
    pub fn named(&self, names: &[&str]) -> String {
        let mut keys = Vec::new();
        for n in names {
            match n.strip_prefix('.') {
                Some(n) => keys.extend(self.pairs.iter().map(|p| format!("'{p}.{n}'"))),
                None => keys.push(format!("'{n}'")),
            }
        }
        format!("{}: keys {}", self.file.display(), keys.join(", "))
    }
}

impl ContactBoundary {
    /// The number of contact pairs.
    pub fn n_pairs(&self) -> usize {
        self.obstacles.len()
    }
}

/// A symmetry-row contact node (`fixed_k`: its Dirichlet values, NaN = free) whose friction
/// would contradict its Dirichlet data, so that it keeps its normal condition without friction
/// (μ = 0, b = 0: λ_τ = 0) in this load step: a prescribed value other than 0, or the pair's
/// obstacle moved or pressed along a prescribed component. On a mirror plane (the value 0, the
/// obstacle symmetric about it) the prescribed tangential part stays 0 and λ (3.28) has none
/// there, so the law holds on the free part; with u_τ prescribed to a value the slip row's
/// force would go into the Dirichlet row and move the node off its value (a block whose
/// side's x was prescribed to 0.05: its corner at 0.0497). Local.
fn friction_inert(pair: &crate::setup::PairSettings, fixed_k: &[f64]) -> bool {
    (fixed_k.iter().enumerate()).any(|(d, v)| {
        !v.is_nan() && (*v != 0.0 || pair.displacement[d] != 0.0 || pair.force_now[d] != 0.0)
    })
}

/// True when every prescribed component d (`fixed_k[d]` not NaN) of a node has n_d = 0: the
/// Dirichlet rows and the contact row (3.29) constrain orthogonal directions.
fn symmetry_row(normal: &[f64; 3], fixed_k: &[f64]) -> bool {
    fixed_k
        .iter()
        .enumerate()
        .all(|(d, v)| v.is_nan() || normal[d].abs() <= 1e-12)
}

/// A start deeper inside the obstacle than this fraction of the body's size (the largest side
/// of its bounding box) is refused as a misplaced obstacle: small-deformation contact cannot
/// close it (the strains would be of that order), and such a start is almost always a wrong
/// position or a normal pointing the wrong way. Overlaps of a few per cent start fine.
pub const DEEP_START_FRACTION: f64 = 0.1;

/// The deepest initial penetration over every rank's contact nodes against
/// [`DEEP_START_FRACTION`] of the body's size: an input error naming `contact.obstacle`, with
/// the node and the likely mistake. Collective.
fn check_depth(
    ctx: &Ctx,
    mesh: &Mesh,
    nodes: &[ContactNode],
    settings: &ContactSettings,
) -> Result<(), RunError> {
    for (p, pair) in settings.pairs.iter().enumerate() {
        let deepest = nodes
            .iter()
            .filter(|k| k.pair == p)
            .min_by(|a, b| a.gap.total_cmp(&b.gap).then(a.tag.cmp(&b.tag)));
        let local = deepest.map_or(f64::INFINITY, |k| k.gap);
        let min_gap = ctx.min_f64(local);
        let size = mesh.extent();
        if min_gap.is_nan() || min_gap >= -DEEP_START_FRACTION * size {
            continue;
        }
        // The rank holding the deepest node (the smallest tag among equal gaps) names it.
        let tag = deepest
            .filter(|k| k.gap == min_gap)
            .map_or(u64::MAX, |k| k.tag);
        let tag = ctx.min_u64(tag);
        let of_pair = || nodes.iter().filter(|k| k.pair == p);
        let penetrating = ctx.sum_usize(of_pair().filter(|k| k.gap < 0.0).count());
        let total = ctx.sum_usize(of_pair().count());
        let hint = if penetrating == total {
            "every contact node starts inside it: is the obstacle on the wrong side of the body, \
             or does its normal point away from the body (it must point from the obstacle into \
             the body)?"
        } else {
            "is the obstacle placed where it should be (units, origin, the sign of a coordinate)?"
        };
        return Err(RunError::Input(
            InputError::new(
                &settings.file,
                format!(
                    "the body starts {:.4e} deep inside the obstacle (contact node {tag}; \
                     {penetrating} of {total} contact nodes inside), {:.0} % of the body's size \
                     {size:.4e} — beyond what small-deformation contact can close \
                     ({:.0} %): {hint}",
                    -min_gap,
                    -100.0 * min_gap / size,
                    100.0 * DEEP_START_FRACTION,
                ),
            )
            .with_key(pair.key("obstacle")),
        ));
    }
    Ok(())
}

/// An input error with the Gmsh tag of the node it names.
type Tagged = (u64, InputError);

/// The contact boundary of every pair: per mesh node its lumped weight w_k and its pair; a
/// node on the facets of two pairs' groups is an input error naming both (the one of smallest
/// tag).
fn pair_nodes(
    mesh: &Mesh,
    settings: &ContactSettings,
) -> (Vec<f64>, Vec<Option<usize>>, Option<Tagged>) {
    let dim = mesh.dim;
    let mut weight = vec![0.0f64; mesh.n_nodes()];
    let mut pair_of: Vec<Option<usize>> = vec![None; mesh.n_nodes()];
    let mut clash = None;
    let mut xs: Vec<[f64; 3]> = Vec::with_capacity(3);
    for (p, pair) in settings.pairs.iter().enumerate() {
        for f in group_facets(mesh, &pair.group) {
            let nodes = mesh.facet(f);
            xs.clear();
            xs.extend(nodes.iter().map(|&v| mesh.coords[v]));
            let (_, m) = fem::facet_normal_measure(&xs);
            for &v in nodes {
                weight[v] += m / dim as f64;
                match pair_of[v] {
                    Some(q) if q != p => {
                        let tag = mesh.node_tags[v];
                        if clash.as_ref().is_some_and(|(t, _)| *t <= tag) {
                            continue;
                        }
                        clash = Some((tag, {
                            let other = &settings.pairs[q];
                            InputError::new(
                                &settings.file,
                                format!(
                                    "mesh node {} at {:?} lies on the contact groups of two \
                                     pairs, \"{}\" ({}) and \"{}\" ({}): a contact node belongs \
                                     to one pair only (split the groups so that they share no \
                                     node)",
                                    mesh.node_tags[v],
                                    &mesh.coords[v][..dim],
                                    other.group,
                                    other.key,
                                    pair.group,
                                    pair.key
                                ),
                            )
                            .with_key(pair.key("group"))
                        }));
                    }
                    _ => pair_of[v] = Some(p),
                }
            }
        }
    }
    (weight, pair_of, clash)
}

/// Builds the owned contact nodes. `fixed` holds the Dirichlet value per mesh dof (NaN = free):
/// a node with a prescribed component is left to its Dirichlet data — unless every prescribed
/// component is orthogonal to the obstacle's normal at the node (a symmetry row: u_x = 0 on
/// the plane x = 0 of a body pressed along z), where both hold: the contact row constrains
/// nᵀu only, which the Dirichlet rows do not touch, and with friction λ (3.28) has no part
/// along a prescribed component (its row of A is the diagonal alone), so the law acts on the
/// free tangential part (docs/method.md, "Symmetry rows on the contact boundary").
/// A node that cannot be projected onto the obstacle is an input error; every rank returns the
/// same result (the collectives run on every path first). Collective.
/// Returns the contact boundary, and what `at_start` makes of its nodes before the obstacles
/// move (the caller's start warnings); `at_start` is collective too, on every rank alike.
pub fn build<W>(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    fixed: &[f64],
    at_start: impl FnOnce(&[ContactNode]) -> W,
) -> Result<(ContactBoundary, W), RunError> {
    let dim = mesh.dim;
    let file = settings.file.as_path();
    let (weight, pair_of, clash) = pair_nodes(mesh, settings);
    ctx.agree_smallest(clash.map(|(tag, e)| (tag, RunError::Input(e))))?;
    let (lo, _) = layout.node_range();
    let mut nodes = Vec::new();
    let mut excluded = 0usize;
    // the unprojectable node of smallest tag
    let mut bad: Option<Tagged> = None;
    for (i, &v) in layout.owned_nodes.iter().enumerate() {
        let Some(p) = pair_of[v] else {
            continue;
        };
        let pair = &settings.pairs[p];
        let x = mesh.coords[v];
        let prescribed = (0..dim).any(|k| !fixed[v * dim + k].is_nan());
        let inert = prescribed && friction_inert(pair, &fixed[v * dim..(v + 1) * dim]);
        if let Obstacle::Body(t) = &pair.obstacle {
            // the rows dual mortar gave the pair (crate::mortar: covered nodes that are contact
            // nodes by the rule below); an uncovered node has none
            if let Some(r) = t.rows.get(&v) {
                let at = Touch {
                    normal: r.normal,
                    gap: r.gap,
                    weight: r.weight,
                    frictionless: inert,
                };
                nodes.push(contact_node(mesh, v, i, lo, p, pair, at));
            } else if prescribed {
                excluded += 1;
            }
            continue;
        }
        let proj = match pair.obstacle.project(x) {
            Ok(p) => p,
            Err(_) if prescribed => {
                excluded += 1;
                continue;
            }
            Err(e) => {
                let tag = mesh.node_tags[v];
                if bad.as_ref().is_none_or(|(t, _)| tag < *t) {
                    let what = format!("contact node {tag} at {:?}: {e}", &x[..dim]);
                    let error = InputError::new(file, what).with_key(pair.key(e.key_in_pair()));
                    bad = Some((tag, error));
                }
                continue;
            }
        };
        if prescribed && !symmetry_row(&proj.normal, &fixed[v * dim..(v + 1) * dim]) {
            excluded += 1;
            continue;
        }
        let at = Touch {
            normal: proj.normal,
            gap: proj.gap,
            weight: weight[v],
            frictionless: inert,
        };
        nodes.push(contact_node(mesh, v, i, lo, p, pair, at));
    }
    let counts: Vec<u64> = ctx.gather(nodes.len() as u64);
    let ex_all = ctx.sum_usize(excluded);
    ctx.agree_smallest(bad.map(|(tag, e)| (tag, RunError::Input(e))))?;
    check_depth(ctx, mesh, &nodes, settings)?;
    let warned = at_start(&nodes);
    move_obstacles(&mut nodes, &settings.displacements(), settings.friction());
    let b = ContactBoundary {
        n_global: counts.iter().sum::<u64>() as usize,
        offset: counts[..ctx.rank].iter().sum::<u64>() as usize,
        nodes,
        on_contact_boundary: pair_of.iter().map(Option::is_some).collect(),
        excluded_dirichlet: ex_all,
        obstacles: settings.pairs.iter().map(|p| p.obstacle.clone()).collect(),
        keys: CaseKeys {
            file: settings.file.clone(),
            pairs: settings.pairs.iter().map(|p| p.key.clone()).collect(),
            solver: String::new(),
        },
        modes: (settings.modes.clone()).unwrap_or_else(|| Arc::new(BodyModes::whole(mesh))),
        stiffness: 0.0,
    };
    Ok((b, warned))
}

/// How a contact node meets its obstacle: its normal n (into the body; unit), gap g_h^k (3.3)
/// and weight w_k — against a rigid obstacle its projection and ∫ φ_k; of a body pair its
/// mortar row's normal, g̃_k / D_kk and D_kk; `frictionless`: the node keeps its normal
/// condition without friction ([`friction_inert`]).
struct Touch {
    normal: [f64; 3],
    gap: f64,
    weight: f64,
    frictionless: bool,
}

/// The contact node of mesh node `v` (owned, local index `i`, first global node `lo`) of
/// pair `p`, meeting its obstacle as `at` says.
fn contact_node(
    mesh: &Mesh,
    v: usize,
    i: usize,
    lo: usize,
    p: usize,
    pair: &crate::setup::PairSettings,
    at: Touch,
) -> ContactNode {
    let Touch {
        normal,
        gap,
        weight,
        frictionless,
    } = at;
    let dim = mesh.dim;
    ContactNode {
        node: v,
        pair: p,
        mu: if frictionless { 0.0 } else { pair.coulomb_mu },
        tag: mesh.node_tags[v],
        row: (lo + i) * dim,
        local_row: i * dim,
        x: mesh.coords[v],
        frame: Frame::new(normal, dim).expect("contact normals are unit vectors"),
        gap,
        weight,
        bound: if frictionless {
            0.0
        } else {
            pair.tresca_threshold.unwrap_or(0.0) * weight
        },
        u_t_ref: [0.0; 2],
    }
}

/// Each pair's obstacle translated by its d (`d[pair]`; docs/obstacles.md, "Moving obstacles"): the node's
/// displacement relative to it is u − d, so the contact condition (3.3) becomes
/// u_n + g0 − d·n ≥ 0 (n, g0 of the undeformed node against the obstacle as given: exact for a
/// planar face while the nearest face stays the same), and with friction the slip is
/// u_τ − d_τ: the tangential reference is d_τ. Local.
fn move_obstacles(nodes: &mut [ContactNode], d: &[[f64; 3]], friction: bool) {
    for k in nodes {
        let d = d[k.pair];
        if d == [0.0; 3] {
            continue;
        }
        k.gap -= dot(d, k.frame.n);
        if friction {
            k.u_t_ref = [dot(d, k.frame.t[0]), dot(d, k.frame.t[1])];
        }
    }
}
