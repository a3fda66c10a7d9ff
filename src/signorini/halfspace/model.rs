//! The model's nodes (all of them, a coarser subset, refined at a predicted edge, or a
//! correction's edge band) and Algorithm 1 on the model (rank 0).

use super::{ModelRun, PairForce, Records, LAMBDA, PAIR, REC, TAG};
use crate::signorini::dense::{coarsen, median_spacing, CMatrix, Dense, DenseLimits, End};
use crate::signorini::rigid::FreeModes;
use crate::tuning::{
    FINE_MODEL_COVER, MAX_MODEL_NODES, MAX_REPRESENTED, MIN_MODEL_NODES, MODEL_BORDER_PART,
    MODEL_MARGIN, SPACING_SAMPLES,
};
use nalgebra::{DMatrix, DVector};

/// The model's nodes among the represented ones (`x`, ordered by the first solve's clearance
/// `s0`): all of them up to `cap` ([`MAX_MODEL_NODES`] for the prediction), else the finest
/// level of the nested iteration's coarsening (about every second node of a contact line,
/// every fourth of a surface, per level) with at most that many, each represented node belonging to the nearest
/// model node (whose weight is the sum of its nodes'; the prediction gives a node its model
/// node's state). Returns (model nodes as indices into `x`, owner of every node of `x`).
pub fn model_nodes(x: &[[f64; 3]], s0: &[f64], cap: usize) -> (Vec<usize>, Vec<usize>) {
    let n = x.len();
    if n <= cap {
        return ((0..n).collect(), (0..n).collect());
    }
    let levels = coarsen(x, s0);
    let kept = match levels.iter().find(|l| l.len() <= cap) {
        Some(l) => l.clone(),
        // no level small enough: the nodes nearest to contact alone (a truncated model)
        None => (0..cap).collect(),
    };
    let d2 = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    let owner = x
        .iter()
        .map(|p| {
            let mut best = (f64::INFINITY, 0);
            for (o, &q) in kept.iter().enumerate() {
                let d = d2(p, &x[q]);
                if d < best.0 {
                    best = (d, o);
                }
            }
            best.1
        })
        .collect();
    (kept, owner)
}

/// A coarsened model ([`model_nodes`]: `kept`, `owner`) refined at the contact edge: every
/// represented node within [`EDGE_BAND`] node spacings of a node on the other side of the
/// edge (`state`: in contact or not, per node of `x`) becomes a model node of its own (the
/// widest band that `cap` allows); the others stay with their coarse model node. A coarse
/// model puts a group of nodes on one side of the edge as a whole, so its edge is off by
/// about a group (measured: the full floating ball at 396 633 unknowns, 4 429 nodes in contact
/// at the end: the coarse model of 1 407 nodes for 6 912 predicted 4 499 and 4 exact steps
/// followed; refined to 2 325 nodes it predicts 4 439, and 2 exact steps follow). Returns the
/// refined (kept, owner), or `None` where the model has no edge or even the narrowest band
/// would exceed `cap`. Local.
pub fn refine_at_edge(
    x: &[[f64; 3]],
    kept: &[usize],
    owner: &[usize],
    state: &[bool],
    cap: usize,
) -> Option<(Vec<usize>, Vec<usize>)> {
    let (m, n) = (kept.len(), x.len());
    if m < 2 || !state.iter().any(|&a| a) || state.iter().all(|&a| a) {
        return None;
    }
    let d2 = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    // the spacing of the model nodes (all of them) and of the nodes (a sample)
    let coarse = median_spacing(&kept.iter().map(|&q| x[q]).collect::<Vec<_>>(), m);
    let spacing = median_spacing(x, SPACING_SAMPLES);
    let mut members = vec![Vec::new(); m];
    for (q, &o) in owner.iter().enumerate() {
        members[o].push(q);
    }
    // the groups near each group: their nodes are the ones a node's band may reach
    let reach2 = (2.0 * coarse + EDGE_BAND[0] * spacing).powi(2);
    let reach = |o: usize, p: usize| d2(&x[kept[o]], &x[kept[p]]) <= reach2;
    // per node: the distance to the nearest node on the other side (within reach)
    let mut across = vec![f64::INFINITY; n];
    for o in 0..m {
        let near: Vec<usize> = (0..m).filter(|&p| reach(o, p)).collect();
        for &q in &members[o] {
            for &p in &near {
                for &j in &members[p] {
                    if state[j] != state[q] {
                        across[q] = across[q].min(d2(&x[q], &x[j]));
                    }
                }
            }
        }
    }
    let mut refined = EDGE_BAND.iter().find_map(|&width| {
        let band = (width * spacing).powi(2);
        let mut own: Vec<usize> = kept.to_vec();
        own.extend((0..n).filter(|&q| across[q] <= band && kept[owner[q]] != q));
        (own.len() <= cap && own.len() > m).then_some(own)
    })?;
    refined.sort_unstable();
    let index: std::collections::HashMap<usize, usize> =
        refined.iter().enumerate().map(|(o, &q)| (q, o)).collect();
    let new_owner = (0..n)
        .map(|q| index.get(&q).copied().unwrap_or(index[&kept[owner[q]]]))
        .collect();
    Some((refined, new_owner))
}

/// Per point of `x`: the squared distance to the nearest point of the other `state` within
/// `reach` (infinity beyond), by a grid of cells of that size. Local.
fn distance_across(x: &[[f64; 3]], state: &[bool], reach: f64) -> Vec<f64> {
    let cell =
        |p: &[f64; 3]| -> [i64; 3] { std::array::from_fn(|k| (p[k] / reach).floor() as i64) };
    let mut grid: std::collections::HashMap<[i64; 3], Vec<usize>> = Default::default();
    for (q, p) in x.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(q);
    }
    let d2 = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    (0..x.len())
        .map(|q| {
            let c = cell(&x[q]);
            let mut best = f64::INFINITY;
            for o in 0..27i64 {
                let key = [c[0] + o % 3 - 1, c[1] + (o / 3) % 3 - 1, c[2] + o / 9 - 1];
                for &j in grid.get(&key).map_or(&[][..], Vec::as_slice) {
                    if state[j] != state[q] {
                        best = best.min(d2(&x[q], &x[j]));
                    }
                }
            }
            if best <= reach * reach {
                best
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// The band of a coarse model refined at the contact edge ([`refine_at_edge`]): the nodes
/// within this many node spacings of a node on the other side, the first width that the cap
/// allows. Not measured as values; not machine-specific.
const EDGE_BAND: [f64; 3] = [2.5, 1.5, 1.0];

/// The edge band of a correction by a coarse model ([`Model::edge_band`]): the nodes within
/// this many node spacings of a node on the other side; where the band exceeds the cap, no
/// correction. Narrower bands (1.5 and 1 spacing, as [`EDGE_BAND`] allows a prediction) cost
/// steps: the committed ball pressed by 0.01 with the model capped at 40 and 50 nodes (test-only
/// limit), bands of 27–32 nodes, took 10 steps against 7 without corrections. Not measured as a
/// value; not machine-specific.
const CORRECTION_BAND: f64 = 2.5;

/// [`MAX_MODEL_NODES`], or the test-only limit that replaces it (`crate::fault::limit`).
pub(super) fn max_model_nodes() -> usize {
    crate::fault::limit("MAX_MODEL_NODES", MAX_MODEL_NODES)
}

/// The nodes of the model, the same on every rank.
pub(super) struct Model {
    /// Contact nodes that penetrate after the first solve.
    pub(super) pen: usize,
    /// The represented contact nodes (global indices), nearest to contact first.
    pub(super) fine: Vec<usize>,
    /// The model node of each represented node (index into `pick`).
    pub(super) owner: Vec<usize>,
    /// The model nodes (global indices), their positions and weights.
    pub(super) pick: Vec<usize>,
    pub(super) x: Vec<[f64; 3]>,
    pub(super) w: Vec<f64>,
    /// A correction's edge band ([`Model::edge_band`]): the nodes it does not represent keep
    /// their state and λ_n.
    pub(super) band: bool,
}

impl Model {
    /// The represented nodes: those nearest to contact, all of them model nodes while that
    /// covers 1.5 × the penetrating ones (the final set of 3D Hertz: 1.23 ×), else a coarser
    /// subset of 3 × as many ([`model_nodes`]), refined at the edge of `edge` (a coarse
    /// prediction's flags of every node, [`refine_at_edge`]); `wanted` (force control) gives
    /// their number, `cap` the most model nodes. Local (the same on every rank).
    pub(super) fn choose(
        all: &[f64],
        wanted: Option<usize>,
        cap: usize,
        edge: Option<&[f64]>,
    ) -> Model {
        let n = all.len() / REC;
        let r = |i: usize| &all[i * REC..(i + 1) * REC];
        // s⁰ = u_n + g: the first solve's clearance (< 0 penetrates); a node that carries a
        // λ_n (a correction's active node, where u_n + g = 0) counts as penetrating
        let s0: Vec<f64> = (0..n)
            .map(|i| {
                let s = r(i)[8] + r(i)[6];
                if r(i)[LAMBDA] != 0.0 {
                    s.min(-f64::MIN_POSITIVE)
                } else {
                    s
                }
            })
            .collect();
        let pen = s0.iter().filter(|&&s| s < 0.0).count();
        let wanted = if let Some(w) = wanted {
            w.min(n)
        } else if pen == 0 {
            0
        } else if FINE_MODEL_COVER[1] * cap >= FINE_MODEL_COVER[0] * pen {
            (MODEL_MARGIN * pen)
                .clamp(MIN_MODEL_NODES.min(cap), cap)
                .min(n)
        } else {
            (MODEL_MARGIN * pen).min(MAX_REPRESENTED).min(n)
        };
        let mut order: Vec<usize> = (0..n).collect();
        // ties by the gmsh tag: the model's nodes and their order (its coarsening, its dense
        // steps) the same on every partition
        order.sort_by(|&a, &b| {
            s0[a]
                .total_cmp(&s0[b])
                .then(r(a)[TAG].total_cmp(&r(b)[TAG]))
        });
        order.truncate(wanted);
        let fine = order;
        let xf: Vec<[f64; 3]> = fine.iter().map(|&i| [r(i)[0], r(i)[1], r(i)[2]]).collect();
        let s0f: Vec<f64> = fine.iter().map(|&i| s0[i]).collect();
        let (mut kept, mut owner) = model_nodes(&xf, &s0f, cap);
        // a second run on a coarse model's own set (`edge`): its edge at full resolution
        if let Some(flags) = edge.filter(|_| kept.len() < fine.len()) {
            let state: Vec<bool> = fine.iter().map(|&i| flags[i] != 0.0).collect();
            if let Some((k, o)) = refine_at_edge(&xf, &kept, &owner, &state, cap) {
                (kept, owner) = (k, o);
            }
        }
        let mut w = vec![0.0; kept.len()];
        for (q, &o) in owner.iter().enumerate() {
            w[o] += r(fine[q])[7];
        }
        Model {
            pen,
            pick: kept.iter().map(|&q| fine[q]).collect(),
            x: kept.iter().map(|&q| xf[q]).collect(),
            fine,
            owner,
            w,
            band: false,
        }
    }

    /// A correction's model where the model of every represented node would be coarser than
    /// the mesh: the represented nodes within [`CORRECTION_BAND`] node spacings of a node on the
    /// other side of the exact update's edge (`updated`, every contact node), or that the update
    /// changes, each a model node of its own; every other node keeps its updated state and its
    /// λ_n (the load it carries is taken from the free modes' load). In Hertzian contact the pressure vanishes at the edge, so moving the edge moves
    /// little load: the held interior's λ_n stay nearly right. `None` where there is no edge or
    /// the band exceeds the cap. Local (the same on every rank).
    pub(super) fn edge_band(&self, all: &[f64], updated: &[f64]) -> Option<Model> {
        let r = |i: usize| &all[i * REC..(i + 1) * REC];
        let x: Vec<[f64; 3]> = self
            .fine
            .iter()
            .map(|&i| [r(i)[0], r(i)[1], r(i)[2]])
            .collect();
        let state: Vec<bool> = self.fine.iter().map(|&i| updated[i] != 0.0).collect();
        let changed: Vec<bool> = (self.fine.iter().zip(&state))
            .map(|(&i, &s)| s != (r(i)[LAMBDA] != 0.0))
            .collect();
        let spacing = median_spacing(&x, SPACING_SAMPLES);
        if !(spacing > 0.0 && spacing.is_finite()) {
            return None;
        }
        let reach = CORRECTION_BAND * spacing;
        let across = distance_across(&x, &state, reach);
        let band: Vec<usize> = (0..x.len())
            .filter(|&q| changed[q] || across[q] <= reach * reach)
            .collect();
        if band.is_empty() || band.len() > max_model_nodes() {
            return None;
        }
        Some(Model {
            pen: self.pen,
            pick: band.iter().map(|&q| self.fine[q]).collect(),
            x: band.iter().map(|&q| x[q]).collect(),
            w: band.iter().map(|&q| r(self.fine[q])[7]).collect(),
            owner: (0..band.len()).collect(),
            fine: band.iter().map(|&q| self.fine[q]).collect(),
            band: true,
        })
    }

    /// G of the model nodes: the free modes' normal parts (`mz` columns), then under force
    /// control one column per force-controlled pair (its nodes' −e·n). Local.
    fn mode_columns(&self, recs: Records, mz: usize, force: &[PairForce]) -> DMatrix<f64> {
        let r = |i: usize| &recs.all[i * REC..(i + 1) * REC];
        let (m, mzf) = (self.m(), mz + force.len());
        DMatrix::from_fn(m, mzf, |q, cc| match force.get(cc.wrapping_sub(mz)) {
            Some(&(e, _, pair)) if cc >= mz => {
                let x = r(self.pick[q]);
                if x[PAIR] == pair as f64 {
                    -(x[3] * e[0] + x[4] * e[1] + x[5] * e[2])
                } else {
                    0.0 // another pair's obstacle stays
                }
            }
            _ => recs.g_all[self.pick[q] * mz + cc],
        })
    }

    /// An edge band's balance: the load in the free modes that the nodes beyond the band carry
    /// at their λ_n stays theirs, so the band balances `phi` less it (m_z entries). Nothing for
    /// another model. Local.
    fn take_held_load(&self, recs: Records, phi: &mut [f64]) {
        if !self.band {
            return;
        }
        let (all, g_all) = (recs.all, recs.g_all);
        let (n, mz) = (all.len() / REC, phi.len());
        let mut inside = vec![false; n];
        self.fine.iter().for_each(|&i| inside[i] = true);
        for i in (0..n).filter(|&i| !inside[i] && all[i * REC + LAMBDA] != 0.0) {
            for (cz, p) in phi.iter_mut().enumerate() {
                *p -= g_all[i * mz + cz] * all[i * REC + LAMBDA];
            }
        }
    }

    /// The model nodes' start set from a set of every contact node (`flags`, nonzero in
    /// contact): a model node is in contact where one of the nodes it represents is. Local.
    pub(super) fn start_set(&self, flags: &[f64]) -> Vec<bool> {
        let mut set = vec![false; self.m()];
        for (q, &i) in self.fine.iter().enumerate() {
            set[self.owner[q]] |= flags[i] != 0.0;
        }
        set
    }

    pub(super) fn m(&self) -> usize {
        self.pick.len()
    }

    /// [`locate`]'s model run (rank 0): [α, the contact nodes of the active model nodes], or
    /// empty.
    pub(super) fn locate(
        &self,
        recs: Records,
        packed_c: &[f64],
        free: &FreeModes,
        phi: &[f64],
        limits: DenseLimits,
    ) -> Vec<f64> {
        let Records { all, g_all } = recs;
        let DenseLimits { c, max_steps } = limits;
        let m = self.m();
        let mz = phi.len();
        let r = |i: usize| &all[i * REC..(i + 1) * REC];
        let cmat = CMatrix::Upper {
            n: m,
            packed: packed_c,
        };
        let d0 = vec![0.0; m];
        let gap: Vec<f64> = self.pick.iter().map(|&i| r(i)[6]).collect();
        let g = DMatrix::from_fn(m, mz, |q, cc| g_all[self.pick[q] * mz + cc]);
        let (_, load_scale) = free.load();
        let dense = Dense {
            cmat,
            d0: &d0,
            gap: &gap,
            g: &g,
            phi,
            load_scale,
            c,
            max_steps,
            pins: None,
        };
        let run = dense.run_nested(vec![false; m], &self.x);
        if run.end != End::Converged {
            return Vec::new();
        }
        let mut packed = run.alpha.clone();
        packed.resize(mz, 0.0);
        let on = self.owner.iter().filter(|&&o| run.active[o]).count();
        packed.push(on as f64);
        packed
    }

    /// Algorithm 1 on the dense model (rank 0): C from the gathered column shares, d₀ = u⁰_n,
    /// the gaps, the free modes (`mz` of them) and their load; under force control (`force`:
    /// e and |F|) the approach as one more free mode (normal parts −e·n, load |F|, as on the
    /// condensed path). Returns [code (0 predicted, 1 no penetration, 2 no convergence, 3
    /// predicted but reaching the border), model nodes, model steps, coarse levels,
    /// represented nodes, the approach's change, flag of every contact node].
    pub(super) fn solve(
        &self,
        recs: Records,
        (packed_c, from): (Vec<f64>, Option<&[f64]>),
        free: &FreeModes,
        spec: &ModelRun,
    ) -> Vec<f64> {
        let all = recs.all;
        let &ModelRun {
            mz,
            limits: DenseLimits { c, max_steps },
            force,
            grow,
        } = spec;
        let n = all.len() / REC;
        let (m, wanted) = (self.m(), self.fine.len());
        let r = |i: usize| &all[i * REC..(i + 1) * REC];
        // an edge band's model: the nodes beyond it keep the state it starts from
        let mut flags = match (self.band, from) {
            (true, Some(f)) => f.to_vec(),
            _ => vec![0.0; n],
        };
        let mut approach = vec![0.0; force.len().max(1)];
        let (code, steps, levels) = if self.pen == 0 && !grow {
            (1.0, 0, 0)
        } else {
            // C stays packed (its upper triangle: half the memory of the full matrix)
            let cmat = CMatrix::Upper {
                n: m,
                packed: &packed_c,
            };
            // a correction: d₀ = u_n + C λ_n, λ_n of a model node the sum of its nodes'
            let mut lam = DVector::<f64>::zeros(m);
            for (q, &i) in self.fine.iter().enumerate() {
                lam[self.owner[q]] += r(i)[LAMBDA];
            }
            let clam = cmat.times(&lam);
            let d0: Vec<f64> = (self.pick.iter().enumerate())
                .map(|(q, &i)| r(i)[8] + clam[q])
                .collect();
            let gap: Vec<f64> = self.pick.iter().map(|&i| r(i)[6]).collect();
            let g = self.mode_columns(recs, mz, force);
            let (_, mut load_scale) = free.load();
            let mut phi = free.free_load();
            phi.truncate(mz);
            self.take_held_load(recs, &mut phi);
            for &(_, magnitude, _) in force {
                phi.push(magnitude);
                load_scale = load_scale.max(magnitude);
            }
            let dense = Dense {
                cmat,
                d0: &d0,
                gap: &gap,
                g: &g,
                phi: &phi,
                load_scale,
                c,
                max_steps,
                pins: None,
            };
            let run = match from {
                Some(flags) => dense.run(self.start_set(flags)),
                None => dense.run_nested(vec![false; m], &self.x),
            };
            if run.end == End::Converged {
                for (j, a) in approach.iter_mut().enumerate() {
                    *a = run.alpha.get(mz + j).copied().unwrap_or(0.0);
                }
                for (q, &i) in self.fine.iter().enumerate() {
                    flags[i] = f64::from(u8::from(run.active[self.owner[q]]));
                }
                let border = wanted - wanted / MODEL_BORDER_PART;
                let truncated = !self.band
                    && wanted < n
                    && self.fine[border..].iter().any(|&i| flags[i] != 0.0);
                (
                    if truncated { 3.0 } else { 0.0 },
                    run.steps.len(),
                    run.coarse.len(),
                )
            } else {
                (2.0, run.steps.len(), run.coarse.len())
            }
        };
        // an edge band represents every contact node (it holds the others)
        let represented = if self.band { n } else { wanted };
        let mut packed = vec![
            code,
            m as f64,
            steps as f64,
            levels as f64,
            represented as f64,
        ];
        packed.extend_from_slice(&approach);
        packed.extend_from_slice(&flags);
        packed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wide_zone_is_modelled_by_a_coarser_subset_whose_nodes_own_their_neighbours() {
        let k = 80; // 6 400 points > MAX_MODEL_NODES
        let x: Vec<[f64; 3]> = (0..k * k)
            .map(|i| [(i % k) as f64 * 0.01, (i / k) as f64 * 0.01, 0.0])
            .collect();
        let s0: Vec<f64> = x.iter().map(|p| p[0] * p[0] + p[1] * p[1]).collect();
        let (kept, owner) = model_nodes(&x, &s0, MAX_MODEL_NODES);
        assert!(
            kept.len() <= MAX_MODEL_NODES && kept.len() >= k * k / 8,
            "{}",
            kept.len()
        );
        assert_eq!(owner.len(), x.len());
        for (o, &q) in kept.iter().enumerate() {
            assert_eq!(owner[q], o, "a model node owns itself");
        }
        // every node lies within the coarsening radius of its owner (≤ 2 spacings here)
        for (q, &o) in owner.iter().enumerate() {
            let p = x[kept[o]];
            let d = ((x[q][0] - p[0]).powi(2) + (x[q][1] - p[1]).powi(2)).sqrt();
            assert!(d <= 0.02 + 1e-12, "node {q}: {d}");
        }
        // up to the cap: every node is a model node
        let (kept, owner) = model_nodes(&x[..100], &s0[..100], MAX_MODEL_NODES);
        assert_eq!(kept, (0..100).collect::<Vec<_>>());
        assert_eq!(owner, kept);
    }

    #[test]
    fn a_coarse_model_is_refined_at_the_edge_of_the_contact_zone_alone() {
        let k = 60; // 3 600 points, coarsened below 1 000
        let x: Vec<[f64; 3]> = (0..k * k)
            .map(|i| [(i % k) as f64 * 0.01, (i / k) as f64 * 0.01, 0.0])
            .collect();
        let r = |p: &[f64; 3]| ((p[0] - 0.3).powi(2) + (p[1] - 0.3).powi(2)).sqrt();
        let s0: Vec<f64> = x.iter().map(|p| r(p) - 0.15).collect();
        let (kept, owner) = model_nodes(&x, &s0, 1000);
        assert!(kept.len() < 1000, "{}", kept.len());
        let state: Vec<bool> = x.iter().map(|p| r(p) < 0.15).collect();
        let (refined, own) = refine_at_edge(&x, &kept, &owner, &state, 3000).expect("fits");
        assert!(refined.len() > kept.len() && refined.len() <= 3000);
        assert!(refined.windows(2).all(|w| w[0] < w[1]), "ordered");
        assert_eq!(own.len(), x.len());
        for (o, &q) in refined.iter().enumerate() {
            assert_eq!(own[q], o, "a model node owns itself");
        }
        // every node near the edge is a model node of its own; far inside and far outside the
        // coarse groups stay, and every node is owned by a model node within two spacings
        for (q, p) in x.iter().enumerate() {
            if (r(p) - 0.15).abs() <= 0.015 {
                assert_eq!(refined[own[q]], q, "node {q} at {p:?} near the edge");
            }
            let o = x[refined[own[q]]];
            let d = ((p[0] - o[0]).powi(2) + (p[1] - o[1]).powi(2)).sqrt();
            assert!(d <= 0.02 + 1e-12, "node {q}: {d}");
        }
        let far = |q: usize| (r(&x[q]) - 0.15).abs() > 0.08;
        assert!((0..x.len()).any(|q| far(q) && refined[own[q]] != q));
        // nothing fits a cap below the coarse model itself; no edge, no refinement
        assert!(refine_at_edge(&x, &kept, &owner, &state, kept.len()).is_none());
        let none = vec![false; x.len()];
        assert!(refine_at_edge(&x, &kept, &owner, &none, 3000).is_none());
    }

    #[test]
    fn a_correction_by_a_coarse_model_runs_on_the_edge_band_alone() {
        let k = 60; // 3 600 records on a grid of spacing 0.01
        let centre = |i: usize| {
            let p = [(i % k) as f64 * 0.01, (i / k) as f64 * 0.01];
            ((p[0] - 0.3).powi(2) + (p[1] - 0.3).powi(2)).sqrt()
        };
        // the exact step's set: the disc r < 0.16 (λ_n ≠ 0); its update: r < 0.15
        let mut all = Vec::new();
        for i in 0..k * k {
            let lam = if centre(i) < 0.16 { -1.0 } else { 0.0 };
            let x = [(i % k) as f64 * 0.01, (i / k) as f64 * 0.01, 0.0];
            all.extend_from_slice(&x);
            all.extend_from_slice(&[0.0, 0.0, 1.0, 0.0, 1e-4, centre(i) - 0.15, 0.0, lam]);
            all.push(i as f64);
        }
        let updated: Vec<f64> = (0..k * k)
            .map(|i| f64::from(u8::from(centre(i) < 0.15)))
            .collect();
        let full = Model::choose(&all, Some(k * k), 1000, None);
        assert!(full.m() < full.fine.len(), "coarsened: {}", full.m());
        let band = full.edge_band(&all, &updated).expect("a band fits");
        assert!(band.band && band.m() == band.fine.len() && band.m() <= MAX_MODEL_NODES);
        assert_eq!(band.owner, (0..band.m()).collect::<Vec<_>>());
        let inside: std::collections::HashSet<usize> = band.fine.iter().copied().collect();
        for i in 0..k * k {
            let r = centre(i);
            // every node the update changes and every node within 2.5 spacings of its edge
            // (one spacing either side of r = 0.15, at least) is in the band; none far off
            if (0.15..0.16).contains(&r) || (r - 0.15).abs() <= 0.01 {
                assert!(inside.contains(&i), "node {i} at r = {r}");
            }
            if (r - 0.15).abs() > 0.04 {
                assert!(!inside.contains(&i), "node {i} at r = {r}");
            }
        }
        // a start without an edge has no band
        let none = vec![0.0; k * k];
        let lifted: Vec<f64> = (0..all.len())
            .map(|j| if j % REC == LAMBDA { 0.0 } else { all[j] })
            .collect();
        assert!(full.edge_band(&lifted, &none).is_none());
    }

    #[test]
    fn distances_across_a_state_edge_within_reach() {
        let x: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
        let state: Vec<bool> = (0..10).map(|i| i < 4).collect();
        let d = distance_across(&x, &state, 2.5);
        assert_eq!(d[3], 1.0);
        assert_eq!(d[4], 1.0);
        assert_eq!(d[2], 4.0);
        assert_eq!(d[5], 4.0);
        assert!(d[0].is_infinite() && d[9].is_infinite() && d[7].is_infinite());
    }
}
