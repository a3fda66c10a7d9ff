//! Contact results: per-node fields (output), the gathered table (contact_nodes.csv), the
//! summary numbers (pressure, total force, half width) and the KKT certificate of (3.14).

use super::boundary::{ContactBoundary, ContactNode, NodeResult};
use crate::contact::Obstacle;
use crate::mesh::Mesh;
use crate::output::{ContactResult, FieldBuf};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::say;
use crate::setup::{self, ContactSettings};
use serde::Serialize;

/// Columns of one gathered contact-node row.
const NCOL: usize = 21;

/// Per owned node: the pressure p^k = −λ_n^k / w_k (THEORY §2).
pub fn pressure(lambda_n: f64, weight: f64) -> f64 {
    if weight > 0.0 {
        -lambda_n / weight
    } else {
        0.0
    }
}

/// What the contact field `state` holds (docs/output.md; the `codes` attribute of its dataset).
pub const STATE_CODES: &str = "1 in contact (in the active set); 0 open (not in contact); -1 not \
     a contact node (a node of the contact surface whose displacement Dirichlet data prescribe: \
     no contact unknowns, its float fields are NaN)";
/// What the contact field `slip_state` holds (friction only).
pub const SLIP_STATE_CODES: &str = "0 stick, 1 slip (nodes in contact, state 1); -1 no \
     tangential state (open nodes and nodes that are not contact nodes, state 0 or -1)";
/// What the contact field `pair` holds (several contact pairs only).
pub const PAIR_CODES: &str = "the node's contact pair: 1, 2, ... in the order of the case's \
     contact tables (contact[0] is 1); 0 not a contact node";

/// The contact surface of this rank: the mesh nodes on the facets of the contact groups that
/// it owns, numbered globally and contiguously by rank (in the order of the global node
/// numbers), and the facets it writes (each by the owner of its node with the smallest global
/// number, who holds every facet at its nodes).
pub struct Surface {
    pub n_global: usize,
    pub offset: usize,
    /// Mesh indices of the owned surface nodes, in owned (global) order.
    pub nodes: Vec<usize>,
    pub n_facets_global: usize,
    pub facet_offset: usize,
    /// `dim` global surface node numbers per owned facet.
    pub facets: Vec<usize>,
    /// Gmsh element tag of each owned facet.
    pub facet_ids: Vec<u64>,
}

/// The contact surface of `groups` (the pairs' groups); `on` marks the mesh nodes on their
/// facets. Collective.
pub fn surface(ctx: &Ctx, mesh: &Mesh, layout: &Layout, groups: &[&str], on: &[bool]) -> Surface {
    let nodes: Vec<usize> = layout
        .owned_nodes
        .iter()
        .copied()
        .filter(|&v| on[v])
        .collect();
    let mine: Vec<u64> = nodes
        .iter()
        .map(|&v| layout.node_global[v] as u64)
        .collect();
    // every surface node's global node number, ascending (ranks own ascending blocks)
    let all = ctx.all_gather_varcount(&mine);
    let counts: Vec<u64> = ctx.gather(nodes.len() as u64);
    let offset = counts[..ctx.rank].iter().sum::<u64>() as usize;
    let mut owned: Vec<usize> = groups
        .iter()
        .flat_map(|g| setup::group_facets(mesh, g))
        .filter(|&f| {
            let first = mesh
                .facet(f)
                .iter()
                .min_by_key(|&&v| layout.node_global[v])
                .expect("a facet has nodes");
            layout.owns_node(*first)
        })
        .collect();
    owned.sort_unstable();
    owned.dedup();
    let mut facets = Vec::with_capacity(owned.len() * mesh.dim);
    for &f in &owned {
        for &v in mesh.facet(f) {
            let g = layout.node_global[v] as u64;
            let k = all
                .binary_search(&g)
                .expect("a facet's nodes are on the contact surface of their owner");
            facets.push(k);
        }
    }
    let facet_counts: Vec<u64> = ctx.gather(owned.len() as u64);
    Surface {
        n_global: all.len(),
        offset,
        nodes,
        n_facets_global: facet_counts.iter().sum::<u64>() as usize,
        facet_offset: facet_counts[..ctx.rank].iter().sum::<u64>() as usize,
        facets,
        facet_ids: owned.iter().map(|&f| mesh.facet_tags[f]).collect(),
    }
}

/// The fields of this rank's contact surface nodes (`nodes`, mesh indices in owned order; the
/// contact nodes `b.nodes` are among them, in the same order): the normal and tangential
/// values, pressure, gap, the state codes ([`STATE_CODES`]); with several pairs the pair; with
/// friction the tangential state ([`SLIP_STATE_CODES`]), |λ_τ| / b_k (on nodes in contact; 0
/// on open ones) and the slip displacement (u_τ on slip nodes, else 0). A surface node that is
/// not a contact node has NaN in every float field and the code −1 (0 for `pair`).
pub fn fields(
    b: &ContactBoundary,
    res: &[NodeResult],
    nodes: &[usize],
    dim: usize,
    friction: bool,
) -> Vec<FieldBuf> {
    let nt = dim - 1;
    // per surface node its contact node, if it is one
    let mut of: Vec<Option<(&ContactNode, &NodeResult)>> = Vec::with_capacity(nodes.len());
    let mut j = 0;
    for &v in nodes {
        if j < b.nodes.len() && b.nodes[j].node == v {
            of.push(Some((&b.nodes[j], &res[j])));
            j += 1;
        } else {
            of.push(None);
        }
    }
    debug_assert_eq!(j, b.nodes.len(), "every contact node is a surface node");
    let float =
        |name: &'static str, ncomp: usize, f: &dyn Fn(&ContactNode, &NodeResult) -> Vec<f64>| {
            let data = of
                .iter()
                .flat_map(|o| match o {
                    Some((k, r)) => f(k, r),
                    None => vec![f64::NAN; ncomp],
                })
                .collect();
            FieldBuf::float(name, ncomp, data)
        };
    let coded = |name: &'static str,
                 codes: &'static str,
                 none: f64,
                 f: &dyn Fn(&ContactNode, &NodeResult) -> f64| FieldBuf {
        name,
        ncomp: 1,
        data: of
            .iter()
            .map(|o| o.map_or(none, |(k, r)| f(k, r)))
            .collect(),
        codes: Some(codes),
    };
    let mut out = vec![
        float("u_n", 1, &|_, r| vec![r.u_n]),
        float("u_t", nt, &|_, r| r.u_t[..nt].to_vec()),
        float("lambda_n", 1, &|_, r| vec![r.lambda_n]),
        float("lambda_t", nt, &|_, r| r.lambda_t[..nt].to_vec()),
        float("pressure", 1, &|k, r| vec![pressure(r.lambda_n, k.weight)]),
        float("gap", 1, &|k, r| vec![r.u_n + k.gap]),
        float("gap0", 1, &|k, _| vec![k.gap]),
        coded("state", STATE_CODES, -1.0, &|_, r| {
            f64::from(u8::from(r.active))
        }),
        float("weight", 1, &|k, _| vec![k.weight]),
        float("contact_force", 3, &|_, r| {
            r.lambda.iter().map(|l| -l).collect()
        }),
    ];
    if b.n_pairs() > 1 {
        // the node's pair, its index from 1 (docs/obstacles.md, "Several contact pairs")
        out.push(coded("pair", PAIR_CODES, 0.0, &|k, _| (k.pair + 1) as f64));
    }
    if friction {
        let slipping = |r: &NodeResult| r.active && r.slip;
        out.push(coded("slip_state", SLIP_STATE_CODES, -1.0, &|_, r| {
            if !r.active {
                -1.0
            } else {
                f64::from(u8::from(r.slip))
            }
        }));
        // |λ_τ| / b_k where the node is in contact; on an open node both are round-off
        out.push(float("friction_ratio", 1, &|k, r| {
            let lt = r.lambda_t[0].hypot(r.lambda_t[1]);
            vec![if r.active && k.bound > 0.0 {
                lt / k.bound
            } else {
                0.0
            }]
        }));
        out.push(float("slip", nt, &|_, r| {
            (0..nt)
                .map(|i| if slipping(r) { r.u_t[i] } else { 0.0 })
                .collect()
        }));
    }
    out
}

/// The contact result of this rank for the output layer: the contact surface of the pairs'
/// groups, the fields on its nodes (the tangential ones with friction), the whole table.
/// Collective.
pub fn contact_result(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    settings: &ContactSettings,
    b: &ContactBoundary,
    res: &[NodeResult],
    table: &Table,
) -> ContactResult {
    let friction = settings.friction();
    let groups: Vec<&str> = settings.pairs.iter().map(|p| p.group.as_str()).collect();
    let s = surface(ctx, mesh, layout, &groups, &b.on_contact_boundary);
    ContactResult {
        n_global: s.n_global,
        offset: s.offset,
        coords: s.nodes.iter().map(|&v| mesh.coords[v]).collect(),
        node_ids: s.nodes.iter().map(|&v| mesh.node_tags[v]).collect(),
        fields: fields(b, res, &s.nodes, mesh.dim, friction),
        n_facets_global: s.n_facets_global,
        facet_offset: s.facet_offset,
        facets: s.facets,
        facet_ids: s.facet_ids,
        csv: table.csv(),
    }
}

/// One row per contact node of the whole set, on every rank, sorted by coordinates.
pub struct Table {
    pub rows: Vec<[f64; NCOL]>,
    pub dim: usize,
}

// Row layout: x y z tag u_n ut1 ut2 l_n lt1 lt2 p gap0 gap weight state b
const X: usize = 0;
const TAG: usize = 3;
const UN: usize = 4;
const UT: usize = 5;
const LN: usize = 7;
const LT: usize = 8;
const P: usize = 10;
const GAP0: usize = 11;
const GAP: usize = 12;
const W: usize = 13;
const STATE: usize = 14;
const BOUND: usize = 15;
const SLIP: usize = 16;
/// The tangential increment u_τ − u_ref friction acts on (= u_τ in a single static solve).
const DUT: usize = 17;
/// The node's contact pair.
const PAIR: usize = 19;
/// Coulomb's μ of the node (0 without Coulomb friction).
const MU: usize = 20;

/// Whether friction acts on a row's node: in contact, or out of contact where a threshold acts
/// (Tresca's b_k acts on every contact node, (3.18)); a Coulomb node out of contact has b_k = 0
/// and no tangential state, whatever threshold an algorithm's last inner solve left there (the
/// fixed point's). It counted as slip: 69 "slip" nodes where 6 were in contact.
fn rubs(r: &[f64; NCOL]) -> bool {
    r[STATE] > 0.5 || (r[BOUND] > 0.0 && r[MU] == 0.0)
}

/// Gathers the contact nodes of all ranks (the contact boundary is small).
pub fn gather(ctx: &Ctx, cs: &ContactBoundary, res: &[NodeResult], dim: usize) -> Table {
    let mut mine: Vec<f64> = Vec::with_capacity(cs.nodes.len() * NCOL);
    for (k, r) in cs.nodes.iter().zip(res) {
        let du_t = super::law::increment(r, k);
        let row = [
            k.x[0],
            k.x[1],
            k.x[2],
            k.tag as f64,
            r.u_n,
            r.u_t[0],
            r.u_t[1],
            r.lambda_n,
            r.lambda_t[0],
            r.lambda_t[1],
            pressure(r.lambda_n, k.weight),
            k.gap,
            r.u_n + k.gap,
            k.weight,
            if r.active { 1.0 } else { 0.0 },
            k.bound,
            if r.slip { 1.0 } else { 0.0 },
            du_t[0],
            du_t[1],
            k.pair as f64,
            k.mu,
        ];
        mine.extend_from_slice(&row);
    }
    let all = ctx.all_gather_varcount(&mine);
    let mut rows: Vec<[f64; NCOL]> = all
        .chunks_exact(NCOL)
        .map(|c| c.try_into().expect("row"))
        .collect();
    rows.sort_by(|a, b| {
        a[..3]
            .partial_cmp(&b[..3])
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(
                a[TAG]
                    .partial_cmp(&b[TAG])
                    .unwrap_or(std::cmp::Ordering::Equal),
            )
    });
    Table { rows, dim }
}

impl Table {
    /// contact_nodes.csv: coordinates first, one row per contact node (with several pairs a
    /// last column `pair`, the pair's index from 1).
    pub fn csv(&self) -> String {
        let several = self.rows.iter().any(|r| r[PAIR] > 0.0);
        let d = self.dim;
        let mut s = String::new();
        let coords = ["x", "y", "z"];
        let mut head: Vec<String> = coords[..d].iter().map(|c| c.to_string()).collect();
        head.push("node_id".into());
        head.push("u_n".into());
        for i in 1..d {
            head.push(format!("u_t{i}"));
        }
        head.push("lambda_n".into());
        for i in 1..d {
            head.push(format!("lambda_t{i}"));
        }
        for h in [
            "pressure",
            "gap0",
            "gap",
            "weight",
            "state",
            "bound",
            "tangential",
        ] {
            head.push(h.into());
        }
        if several {
            head.push("pair".into());
        }
        s.push_str(&head.join(","));
        s.push('\n');
        for r in &self.rows {
            let mut v: Vec<String> = r[..d].iter().map(|x| format!("{x:.17e}")).collect();
            v.push(format!("{}", r[TAG] as u64));
            v.push(format!("{:.17e}", r[UN]));
            for i in 0..d - 1 {
                v.push(format!("{:.17e}", r[UT + i]));
            }
            v.push(format!("{:.17e}", r[LN]));
            for i in 0..d - 1 {
                v.push(format!("{:.17e}", r[LT + i]));
            }
            for c in [P, GAP0, GAP, W] {
                v.push(format!("{:.17e}", r[c]));
            }
            v.push(if r[STATE] > 0.5 { "active" } else { "inactive" }.into());
            v.push(format!("{:.17e}", r[BOUND]));
            v.push(
                if r[SLIP] > 0.5 && rubs(r) {
                    "slip"
                } else if r[BOUND] > 0.0 && rubs(r) {
                    "stick"
                } else {
                    "-"
                }
                .into(),
            );
            if several {
                v.push(format!("{}", r[PAIR] as usize + 1));
            }
            s.push_str(&v.join(","));
            s.push('\n');
        }
        s
    }

    /// The mean contact mesh size h_c: the mean of w_k^(1/(d−1)) over the contact nodes (0
    /// without any).
    pub fn mesh_size(&self) -> f64 {
        let e = 1.0 / (self.dim - 1) as f64;
        let n = self.rows.len();
        let s: f64 = self.rows.iter().map(|r| r[W].max(0.0).powf(e)).sum();
        if n > 0 {
            s / n as f64
        } else {
            0.0
        }
    }

    pub fn active_count(&self) -> usize {
        self.rows.iter().filter(|r| r[STATE] > 0.5).count()
    }

    pub fn max_pressure(&self) -> f64 {
        self.rows.iter().map(|r| r[P]).fold(0.0, f64::max)
    }

    /// Half width of the contact zone for a flat obstacle in 2D, from the pressure profile:
    /// least-squares fit of p² = a − κ (s − s_c)² over the active nodes (Hertz: p² is linear
    /// in s²), s the tangential coordinate, s_c the pressure-weighted centre — or, when one end
    /// of the active nodes carries at least half the largest pressure (a zone cut by a mirror
    /// plane), that end; b = sqrt(a / κ). None with fewer than 3 active nodes or another obstacle /
    /// dimension. `pair`: only the nodes of that pair.
    pub fn half_width(&self, obstacle: &Obstacle, pair: Option<usize>) -> Option<f64> {
        let Obstacle::Plane(pl) = obstacle else {
            return None;
        };
        if self.dim != 2 {
            return None;
        }
        let n = pl.normal();
        let tau = [n[1], -n[0]];
        let pts: Vec<(f64, f64)> = self
            .rows
            .iter()
            .filter(|r| r[STATE] > 0.5 && r[P] > 0.0)
            .filter(|r| pair.is_none_or(|p| r[PAIR] == p as f64))
            .map(|r| (r[X] * tau[0] + r[X + 1] * tau[1], r[P]))
            .collect();
        if pts.len() < 3 {
            return None;
        }
        // a Hertz zone's pressure falls to 0 at its edges: an end node that carries at least
        // half the largest pressure is on a mirror plane through the zone's centre
        let p_max = pts.iter().map(|p| p.1).fold(0.0, f64::max);
        let (mut lo, mut hi) = (pts[0], pts[0]);
        for &p in &pts {
            if p.0 < lo.0 {
                lo = p;
            }
            if p.0 > hi.0 {
                hi = p;
            }
        }
        let sc = match (2.0 * lo.1 >= p_max, 2.0 * hi.1 >= p_max) {
            (true, false) => lo.0,
            (false, true) => hi.0,
            _ => {
                let sp: f64 = pts.iter().map(|p| p.1).sum();
                pts.iter().map(|p| p.0 * p.1).sum::<f64>() / sp
            }
        };
        // p² = a + m z with z = (s − s_c)², m = −κ
        let np = pts.len() as f64;
        let (mut sz, mut sy, mut szz, mut szy) = (0.0, 0.0, 0.0, 0.0);
        for &(s, p) in &pts {
            let z = (s - sc) * (s - sc);
            let y = p * p;
            sz += z;
            sy += y;
            szz += z * z;
            szy += z * y;
        }
        let det = np * szz - sz * sz;
        if det.abs() < f64::MIN_POSITIVE {
            return None;
        }
        let m = (np * szy - sz * sy) / det;
        let a = (sy - m * sz) / np;
        if m >= 0.0 || a <= 0.0 {
            return None;
        }
        let b = (a / -m).sqrt();
        // Not a Hertz-like profile (e.g. a uniform pressure): no meaningful half width.
        let reach = pts.iter().map(|p| (p.0 - sc).abs()).fold(0.0, f64::max);
        (b <= 2.0 * reach).then_some(b)
    }

    /// Friction certificate of (3.18): max(|λ_τ| − b_k, 0), max |u_τ| on stick nodes, and the
    /// alignment defect |λ_τ − b_k u_τ/|u_τ|| on slip nodes, with the scales. u_τ is the
    /// increment since the previous load step; b_k the final μ(−λ_n^k) with Coulomb.
    pub fn friction_certificate(&self) -> FrictionCertificate {
        let (mut excess, mut stick, mut align, mut bmax, mut umax) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let (mut n_stick, mut n_slip) = (0usize, 0usize);
        let mut total = 0.0f64; // the largest |u| at the contact, increments or not
        for r in &self.rows {
            let ut = [r[DUT], r[DUT + 1]];
            umax = umax
                .max((ut[0] * ut[0] + ut[1] * ut[1]).sqrt())
                .max(r[UN].abs());
            total = total.max(r[UT].hypot(r[UT + 1]));
        }
        // A slip node whose increment is below the certificate's tolerance (a node at the slip
        // limit that did not move in this load step) is at rest: (3.18) then asks |λ_τ| ≤ b only.
        let rest = RESTING_SLIP * umax.max(total);
        for r in &self.rows {
            let mut ut = [r[DUT], r[DUT + 1]];
            let lt = [r[LT], r[LT + 1]];
            let slip = r[SLIP] > 0.5;
            if slip && (ut[0] * ut[0] + ut[1] * ut[1]).sqrt() <= rest {
                ut = [0.0; 2];
            }
            let res = crate::contact::tangential_residual(&ut, &lt, r[BOUND], slip);
            excess = excess.max(res.excess);
            stick = stick.max(res.stick_motion);
            align = align.max(res.slip_alignment);
            bmax = bmax.max(r[BOUND]);
            if !rubs(r) {
                continue;
            }
            if slip {
                n_slip += 1;
            } else {
                n_stick += 1;
            }
        }
        FrictionCertificate {
            max_excess: excess,
            max_stick_motion: stick,
            max_slip_alignment_defect: align,
            bound_scale: bmax,
            length_scale: umax,
            stick_count: n_stick,
            slip_count: n_slip,
        }
    }

    /// KKT certificate of (3.14) (and λ_τ = 0 for frictionless contact): the largest
    /// violations over all contact nodes, with the problem's scales to judge them by.
    pub fn kkt(&self, frictionless: bool, scales: &Scales) -> Kkt {
        let mut pen = 0.0f64;
        let mut pos = 0.0f64;
        let mut comp = 0.0f64;
        let mut lt = 0.0f64;
        let mut lscale = 0.0f64;
        let mut uscale = 0.0f64;
        for r in &self.rows {
            pen = pen.max(-r[GAP]);
            pos = pos.max(r[LN]);
            comp = comp.max((r[LN] * r[GAP]).abs());
            let ltn = (r[LT] * r[LT] + r[LT + 1] * r[LT + 1]).sqrt();
            lt = lt.max(ltn);
            lscale = lscale.max(r[LN].abs());
            uscale = uscale.max(r[UN].abs()).max(r[GAP0].abs());
        }
        Kkt {
            max_penetration: pen.max(0.0),
            max_positive_lambda_n: pos.max(0.0),
            max_complementarity: comp,
            force_scale: if scales.force > 0.0 {
                scales.force
            } else {
                lscale
            },
            length_scale: scales.length.max(uscale),
            max_abs_lambda_t: frictionless.then_some(lt),
        }
    }
}

/// The scales of a whole problem: the largest nodal load |f|_∞ and the largest displacement
/// |u|_∞ (a certificate judged by the contact nodes' own values alone calls round-off a
/// violation where everything at the contact is tiny, e.g. a block lifted off).
#[derive(Clone, Copy, Debug, Default)]
pub struct Scales {
    pub force: f64,
    pub length: f64,
}

/// A slip node's tangential increment at most this fraction of the largest contact
/// displacement counts as no motion in the friction certificate: the certificate's own
/// tolerance, since a stick node may move that much too (a node at the slip limit that did not
/// move in a load step — e.g. after a fixed point stopped at max|Δb| ≤ 1e-9 max b — has an
/// increment of solver-tolerance size whose direction means nothing).
pub const RESTING_SLIP: f64 = CERTIFICATE_TOL;

/// summary.json's "contact" section.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    pub nodes: usize,
    pub excluded_dirichlet: usize,
    pub active_count: usize,
    pub max_pressure: f64,
    pub total_force: Vec<f64>,
    /// A moving obstacle (`contact.motion`): its displacement d in this solve.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub obstacle_displacement: Option<Vec<f64>>,
    /// Force control (`contact.force`): the approach δ solved for (the obstacle moved by
    /// δ F/|F|).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub approach: Option<f64>,
    pub half_width: Option<f64>,
    /// Several contact pairs: each pair's numbers (the fields above are over all pairs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pairs: Option<Vec<PairSummary>>,
    pub kkt: Kkt,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionCertificate>,
    /// The problem's scales the certificates were judged by (not written).
    #[serde(skip)]
    pub scales: Scales,
}

/// summary.json's `contact.pairs[i]` (cases with several pairs): one pair's numbers.
#[derive(Debug, Clone, Serialize)]
pub struct PairSummary {
    /// The pair's table in the case file (`contact[i]`).
    pub key: String,
    pub group: String,
    pub nodes: usize,
    pub active_count: usize,
    pub max_pressure: f64,
    /// Σ_k −λ^k over the pair's nodes: the force of the body on the obstacle.
    pub total_force: Vec<f64>,
    /// The obstacle's displacement d (a pair with `motion` or `force`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub obstacle_displacement: Option<Vec<f64>>,
    /// Force control: the approach δ solved for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub approach: Option<f64>,
    /// 2D, a plane: the half width of the pair's contact zone ([`Table::half_width`]).
    pub half_width: Option<f64>,
    /// 3D: Σ w_k over the pair's active nodes.
    pub contact_area: Option<f64>,
}

/// Every pair's obstacle where the solve left it: its displacement d and, under force
/// control, its approach δ (`None` for the other pairs).
pub struct Placement {
    pub displacement: Vec<[f64; 3]>,
    pub approach: Vec<Option<f64>>,
}

/// Fills summary.json's obstacle displacement and approach of `contact` and, with several
/// pairs, its per-pair numbers (`placed`: each pair's d and δ). `contact.approach` is the δ of the one pair
/// under force control (with several such pairs each has its own in `pairs`). Collective.
pub fn per_pair(
    ctx: &Ctx,
    settings: &ContactSettings,
    b: &ContactBoundary,
    res: &[NodeResult],
    table: &Table,
    placed: &Placement,
    contact: &mut ContactSummary,
) {
    let (displacement, approach) = (&placed.displacement, &placed.approach);
    let dim = table.dim;
    let moves = |p: &crate::setup::PairSettings| p.motion.is_some() || p.force.is_some();
    contact.approach = match approach.iter().flatten().collect::<Vec<_>>().as_slice() {
        [&one] => Some(one),
        _ => None,
    };
    if let [pair] = settings.pairs.as_slice() {
        if moves(pair) {
            contact.obstacle_displacement = Some(displacement[0][..dim].to_vec());
        }
        return;
    }
    let np = settings.pairs.len();
    let mut local = vec![0.0; 3 * np];
    for (k, r) in b.nodes.iter().zip(res) {
        for c in 0..3 {
            local[3 * k.pair + c] -= r.lambda[c];
        }
    }
    let force = ctx.sum_vec(&local);
    let pairs = settings
        .pairs
        .iter()
        .enumerate()
        .map(|(p, pair)| {
            let rows = || table.rows.iter().filter(move |r| r[PAIR] == p as f64);
            let active = || rows().filter(|r| r[STATE] > 0.5);
            PairSummary {
                key: pair.key.clone(),
                group: pair.group.clone(),
                nodes: rows().count(),
                active_count: active().count(),
                max_pressure: rows().map(|r| r[P]).fold(0.0, f64::max),
                total_force: force[3 * p..3 * p + dim].to_vec(),
                obstacle_displacement: moves(pair).then(|| displacement[p][..dim].to_vec()),
                approach: approach[p].filter(|_| pair.force.is_some()),
                half_width: table.half_width(&b.obstacles[p], Some(p)),
                contact_area: (dim == 3).then(|| active().map(|r| r[W]).sum()),
            }
        })
        .collect::<Vec<_>>();
    for s in &pairs {
        say!(
            ctx,
            "contact ({}): {} active, p_max = {:.6}, total force = {:?}{}",
            s.key,
            s.active_count,
            s.max_pressure,
            s.total_force,
            s.approach
                .map(|d| format!(", approach {d:.6e}"))
                .unwrap_or_default()
        );
    }
    contact.pairs = Some(pairs);
}

/// The relative violation of a certificate beyond which a final state is not accepted.
pub const CERTIFICATE_TOL: f64 = 1e-6;

/// Σ_k −λ^k over all ranks (global components).
pub fn total_force(ctx: &Ctx, res: &[NodeResult]) -> [f64; 3] {
    let mut t = [0.0; 3];
    for r in res {
        for k in 0..3 {
            t[k] -= r.lambda[k];
        }
    }
    let out = ctx.sum_vec(&t);
    [out[0], out[1], out[2]]
}

/// The largest violations of (3.14) (and of λ_τ = 0 without friction) over all contact nodes,
/// with the scales to judge them by.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Kkt {
    pub max_penetration: f64,
    pub max_positive_lambda_n: f64,
    pub max_complementarity: f64,
    pub force_scale: f64,
    pub length_scale: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_abs_lambda_t: Option<f64>,
}

impl Kkt {
    /// The worst violation of (3.14) relative to its scale (above 1e-8: an inexact linear
    /// solve; above [`CERTIFICATE_TOL`]: not a solution; the per-step number of history.csv).
    pub fn worst(&self) -> f64 {
        let (fs, ls) = (self.force_scale, self.length_scale);
        [
            ratio(self.max_penetration, ls),
            ratio(self.max_positive_lambda_n, fs),
            ratio(self.max_complementarity, fs * ls),
            ratio(self.max_abs_lambda_t.unwrap_or(0.0), fs),
        ]
        .into_iter()
        .fold(0.0, f64::max)
    }
}

/// v / scale; 0 for v = 0 and infinity for v > 0 at a zero scale (so that `ratio > rel` ⇔
/// `v > rel · scale`).
pub fn ratio(v: f64, scale: f64) -> f64 {
    if v <= 0.0 {
        0.0
    } else if scale > 0.0 {
        v / scale
    } else {
        f64::INFINITY
    }
}

impl FrictionCertificate {
    /// The worst violation of (3.18) relative to the problem's scales `scales` (or the
    /// certificate's own where larger; the per-step number of history.csv).
    pub fn worst(&self, scales: &Scales) -> f64 {
        let force = scales.force.max(self.bound_scale);
        let length = scales.length.max(self.length_scale);
        ratio(self.max_excess, force)
            .max(ratio(self.max_stick_motion, length))
            .max(ratio(self.max_slip_alignment_defect, force))
    }
}

/// The friction certificate of (3.18).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FrictionCertificate {
    pub max_excess: f64,
    pub max_stick_motion: f64,
    pub max_slip_alignment_defect: f64,
    pub bound_scale: f64,
    pub length_scale: f64,
    pub stick_count: usize,
    pub slip_count: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kkt(pen: f64) -> Kkt {
        Kkt {
            max_penetration: pen,
            max_positive_lambda_n: 0.0,
            max_complementarity: 0.0,
            force_scale: 1.0,
            length_scale: 2.0,
            max_abs_lambda_t: Some(0.0),
        }
    }

    #[test]
    fn kkt_violations_relative_to_the_scales() {
        assert!(kkt(1e-9).worst() <= 1e-8);
        assert!(kkt(1e-7).worst() > 1e-8);
        assert!(kkt(1e-7).worst() <= CERTIFICATE_TOL);
        assert!((kkt(1e-7).worst() - 0.5e-7).abs() < 1e-22);
        assert_eq!(kkt(0.0).worst(), 0.0);
        let mut k = kkt(0.0);
        k.max_abs_lambda_t = Some(1e-3);
        assert!(k.worst() > CERTIFICATE_TOL);
    }

    /// One contact row: total u_τ, increment Δu_τ, λ_τ, b, slip flag.
    fn row(ut: f64, dut: f64, lt: f64, b: f64, slip: bool) -> [f64; NCOL] {
        let mut r = [0.0; NCOL];
        r[UT] = ut;
        r[DUT] = dut;
        r[LT] = lt;
        r[LN] = -b * 10.0;
        r[BOUND] = b;
        r[STATE] = 1.0;
        r[SLIP] = if slip { 1.0 } else { 0.0 };
        r
    }

    #[test]
    fn certificate_judges_the_increment() {
        // a stick node that moved in an earlier load step (u_τ ≠ 0, Δu_τ = 0) and a slip node
        // whose increment is round-off (at rest at the limit): both fine
        let t = Table {
            rows: vec![
                row(0.5, 0.0, 0.05, 0.1, false),
                row(0.5, 1e-17, 0.1, 0.1, true),
                row(0.7, 0.2, 0.1, 0.1, true),
            ],
            dim: 2,
        };
        let c = t.friction_certificate();
        assert_eq!(c.max_stick_motion, 0.0);
        assert!(c.max_slip_alignment_defect <= 1e-15, "{c:?}");
        assert_eq!((c.stick_count, c.slip_count), (1, 2));
        // a Coulomb node out of contact is neither (whatever its threshold); a Tresca node out
        // of contact with a threshold is counted
        let mut open = row(0.0, 0.0, 0.0, 1e-3, true);
        open[STATE] = 0.0;
        open[MU] = 0.3;
        let mut tresca = row(0.0, 0.0, 0.0, 1e-3, false);
        tresca[STATE] = 0.0;
        let t = Table {
            rows: vec![row(0.5, 1e-17, 0.1, 0.1, true), open, tresca],
            dim: 2,
        };
        let c = t.friction_certificate();
        assert_eq!((c.stick_count, c.slip_count), (1, 1));
        // a stick node with an increment, a slip node against its increment: violations
        let t = Table {
            rows: vec![
                row(0.5, 0.01, 0.05, 0.1, false),
                row(0.7, 0.2, -0.1, 0.1, true),
            ],
            dim: 2,
        };
        let c = t.friction_certificate();
        assert_eq!(c.max_stick_motion, 0.01);
        assert!((c.max_slip_alignment_defect - 0.2).abs() < 1e-15, "{c:?}");
    }

    #[test]
    fn friction_beyond_its_bound_is_a_violation() {
        let scales = Scales {
            force: 1.0,
            length: 1.0,
        };
        let mut c = FrictionCertificate {
            max_excess: 0.0,
            max_stick_motion: 1e-12,
            max_slip_alignment_defect: 1e-12,
            bound_scale: 0.1,
            length_scale: 1.0,
            stick_count: 3,
            slip_count: 2,
        };
        assert!(c.worst(&scales) <= CERTIFICATE_TOL);
        assert!((c.worst(&scales) - 1e-12).abs() < 1e-27);
        c.max_excess = 2.0; // |λ_τ| 20 × b_k
        assert!(c.worst(&scales) > CERTIFICATE_TOL);
        assert_eq!(c.worst(&scales), 2.0);
    }
}
