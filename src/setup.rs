//! Case → domain: the one place that turns case-file sections into the values the stages
//! below work on (the mesh with its material, the linear problem, the contact settings).

use crate::assembly::{BodyForce, FacetLoad, FacetLoadKind, Problem};
use crate::case::{self, vec3, BodyForceSpec, Case, ContactSection, Friction, NewtonSection};
use crate::contact::Obstacle;
use crate::dist;
use crate::error::{InputError, RunError};
use crate::fem::{self, Material, Materials};
use crate::mesh::{self, Mesh};
use crate::par::Ctx;
use crate::partition::Layout;
use crate::say;
use crate::warnings::{self, Warning};
use std::path::Path;

/// The mesh (this rank's part: local indices) with its layout, and the materials of a case
/// (each local cell's), checked against each other.
pub struct Input {
    pub mesh: Mesh,
    pub material: Materials,
    pub layout: Layout,
    pub read_seconds: f64,
    pub partition_seconds: f64,
    /// The warnings of the input ([`locking_warnings`]), logged; for summary.json.
    pub warnings: Vec<Warning>,
}

/// The ranks read the case's mesh distributed (`crate::dist`: each rank keeps its part),
/// partition it and check the case against it; all ranks agree on an error. Logs the mesh line
/// and the local sizes.
pub fn read_input(ctx: &Ctx, case: &Case) -> Result<Input, RunError> {
    let refine = dist::Refine {
        level: case.mesh.refine,
        project: &case.mesh.project,
        check: &|dim, groups| case.check_projections(dim, groups),
    };
    // the unknowns after the refinement: each level splits a cell into 2^dim, about as many
    // more nodes
    let levels = case.mesh.refine.min(10);
    let lengths = |dim: usize, extent, far, nodes: usize| {
        case.check_mesh_lengths(dim, extent, far, (nodes * dim) << (dim * levels))
    };
    let d = dist::read_distributed(ctx, &case.mesh.file, &refine, &lengths)?;
    let model = ctx.agree(check(case, &d.mesh).map_err(RunError::from))?;
    let unknowns = d.mesh.n_nodes_global() * d.mesh.dim;
    ctx.agree(
        case.check_magnitudes(d.mesh.dim, d.mesh.extent(), unknowns)
            .map_err(RunError::from),
    )?;
    facet_groups(ctx, case, &d.mesh)?;
    let mut material = cell_materials(ctx, case, &d.mesh, model)?;
    material.reference = reference_material(ctx, case, &d.mesh, &material);
    (material.half_space, material.slave_over_master) = pair_modulus(ctx, case, &d.mesh, &material);
    ctx.agree_smallest(check_body_force(case, &d.mesh).map(|(t, e)| (t, e.into())))?;
    let overridden = dirichlet_overridden(ctx, case, &d.mesh, &d.layout);
    let input = Input {
        warnings: [locking_warnings(case, &material), overridden].concat(),
        mesh: d.mesh,
        material,
        layout: d.layout,
        read_seconds: d.read_seconds,
        partition_seconds: d.partition_seconds,
    };
    let mesh = &input.mesh;
    let dim = mesh.dim;
    say!(
        ctx,
        "mesh {}{}: {}D, {} nodes, {} cells, {} boundary facets, groups: {}",
        case.mesh.file.display(),
        match case.mesh.refine {
            0 => String::new(),
            k => format!(" refined {k}x"),
        },
        dim,
        mesh.n_nodes_global(),
        mesh.n_cells_global(),
        mesh.n_facets_global(),
        mesh.groups
            .iter()
            .enumerate()
            .map(|(i, g)| format!("{} ({}D, {})", g.name, g.dim, mesh.group_size_global(i)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let local = [mesh.n_cells() as u64, mesh.n_nodes() as u64];
    let per_rank = ctx.all_gather_varcount(&local);
    say!(
        ctx,
        "local mesh per rank (cells with ghosts, nodes with ghosts): {:?}",
        per_rank
            .chunks_exact(2)
            .map(|c| (c[0], c[1]))
            .collect::<Vec<_>>()
    );
    warnings::log(ctx, &input.warnings, "");
    Ok(input)
}

/// Poisson's ratio from which P1 locking is warned about (plane strain and 3D).
pub const NEARLY_INCOMPRESSIBLE: f64 = 0.49;

/// The warnings of materials whose Poisson's ratio is at least [`NEARLY_INCOMPRESSIBLE`]
/// (plane strain and 3D), one per material: P1 elements lock there. Pure.
fn locking_warnings(case: &Case, material: &Materials) -> Vec<Warning> {
    let mut list = Vec::new();
    for (m, section) in material.list.iter().zip(&case.materials) {
        let nu = m.poisson;
        if nu >= NEARLY_INCOMPRESSIBLE && m.model != fem::Model::PlaneStress {
            let whose = match &section.group {
                None => String::new(),
                Some(_) => format!("{}: ", section.key),
            };
            list.push(Warning {
                code: warnings::NEARLY_INCOMPRESSIBLE,
                message: format!(
                    "{whose}poisson = {nu} is close to 1/2: linear (P1) elements lock in \
                     the nearly incompressible limit — displacements come out too small and \
                     stresses and contact pressures too large (Hertz disk, default mesh: p_max \
                     off by 1 % at 0.45, 4 % at 0.49, 26 % at 0.499, 90 % at 0.4999)"
                ),
                key: Some(format!("{}.poisson", section.key)),
                pair: None,
                value: nu,
                threshold: NEARLY_INCOMPRESSIBLE,
                at: None,
                steps: Vec::new(),
            });
        }
    }
    list
}

fn check(case: &Case, mesh: &Mesh) -> Result<fem::Model, InputError> {
    let groups: Vec<(String, usize)> = mesh
        .groups
        .iter()
        .map(|g| (g.name.clone(), g.dim))
        .collect();
    case.check_against_mesh(mesh.dim, &groups)?;
    let sized: Vec<(String, usize, usize)> = (groups.into_iter().enumerate())
        .map(|(i, (name, dim))| (name, dim, mesh.group_size_global(i)))
        .collect();
    case.check_groups_used(mesh.dim, &sized)?;
    Ok(model_of(case.model(mesh.dim)?))
}

/// The facets of the load and contact groups ([`Case::facet_group_fault`]), each rank checking
/// its own: the error names the first such group in the case's order and its faulty facet of
/// smallest gmsh tag over all ranks, the same on every rank count. Collective.
fn facet_groups(ctx: &Ctx, case: &Case, mesh: &Mesh) -> Result<(), RunError> {
    let fault = case.facet_group_fault(mesh);
    let first = ctx.min_u64(fault.as_ref().map_or(u64::MAX, |f| f.0 as u64));
    let fault = fault.filter(|f| f.0 as u64 == first);
    ctx.agree_smallest(fault.map(|(_, tag, e)| (tag, RunError::Input(e))))
}

/// [`warnings::DIRICHLET_OVERRIDDEN`]: nodes whose component two `[[dirichlet]]` entries on
/// different groups prescribe differently — other values, or one ramped with the load and one
/// held (`ramp = false`) at a value that is not zero: the later entry's value holds (a corner
/// shared by `top` = [0, −0.01] and `right` = [0.02, "free"] moves by [0.02, −0.01]). A later
/// entry on the same group overrides on purpose (examples/sphere_drag.toml holds `bottom` at
/// 0, then moves its x by 0.004): no warning. Entries that agree on a shared node (a clamped
/// bottom and a symmetry side at a corner) are fine. Named by the node of smallest tag, the
/// same on every rank count. Collective (one gather).
fn dirichlet_overridden(ctx: &Ctx, case: &Case, mesh: &Mesh, layout: &Layout) -> Vec<Warning> {
    let dim = mesh.dim;
    // per local node and component: the entry whose value holds so far
    let mut by: Vec<Option<usize>> = vec![None; mesh.n_nodes() * dim];
    // (count, tag, earlier, later, component) of the owned nodes
    let (mut count, mut first) = (0usize, None::<(u64, usize, usize, usize, usize)>);
    let mut owned = vec![false; mesh.n_nodes()];
    for &v in &layout.owned_nodes {
        owned[v] = true;
    }
    for (j, d) in case.dirichlet.iter().enumerate() {
        for g in groups_named(mesh, &d.group) {
            for &v in mesh.group_nodes(g).iter() {
                for (k, val) in d.value.iter().enumerate().take(dim) {
                    let Some(x) = val else { continue };
                    let slot = &mut by[v * dim + k];
                    if let Some(i) = *slot {
                        let e = &case.dirichlet[i];
                        let y = e.value[k].unwrap_or(f64::NAN);
                        let same = *x == y && (e.ramp == d.ramp || *x == 0.0);
                        if !same && e.group != d.group && owned[v] {
                            count += 1;
                            let tag = mesh.node_tags[v];
                            if first.is_none_or(|f| tag < f.0) {
                                first = Some((tag, i, j, k, v));
                            }
                        }
                    }
                    *slot = Some(j);
                }
            }
        }
    }
    // every rank's first (each node counted by the rank that owns it)
    let mine: Vec<f64> = match first {
        Some((tag, i, j, k, v)) => {
            let x = mesh.coords[v];
            vec![tag as f64, i as f64, j as f64, k as f64, x[0], x[1], x[2]]
        }
        None => Vec::new(),
    };
    let total = ctx.sum_usize(count);
    let all = ctx.all_gather_varcount(&mine);
    let Some(r) = all.chunks_exact(7).min_by(|a, b| a[0].total_cmp(&b[0])) else {
        return Vec::new();
    };
    let (tag, i, j, k) = (r[0] as u64, r[1] as usize, r[2] as usize, r[3] as usize);
    let (a, b) = (&case.dirichlet[i], &case.dirichlet[j]);
    let shown = |d: &case::Dirichlet| {
        let x = d.value[k].unwrap_or(f64::NAN);
        if d.ramp {
            format!("{x}")
        } else {
            format!("{x} held (ramp = false)")
        }
    };
    let x = &r[4..4 + dim];
    vec![Warning {
        code: warnings::DIRICHLET_OVERRIDDEN,
        message: format!(
            "dirichlet[{j}] (group \"{}\") overrides dirichlet[{i}] (group \"{}\") at {total} \
             node component(s) they share, e.g. component {k} of node {tag} at {}: {} instead \
             of {} — the later entry's value holds; is that the intent?",
            b.group,
            a.group,
            warnings::coords(x),
            shown(b),
            shown(a)
        ),
        key: Some(format!("dirichlet[{j}].value")),
        pair: None,
        value: total as f64,
        threshold: 0.0,
        at: Some(warnings::Place {
            node: Some(tag),
            cell: None,
            x: x.to_vec(),
        }),
        steps: Vec::new(),
    }]
}

fn model_of(m: case::MaterialModel) -> fem::Model {
    match m {
        case::MaterialModel::PlaneStrain => fem::Model::PlaneStrain,
        case::MaterialModel::PlaneStress => fem::Model::PlaneStress,
        case::MaterialModel::ThreeD => fem::Model::Solid,
    }
}

/// The material of every local cell: `[material]`'s for all; with `[[material]]` the entry
/// whose volume group holds the cell (own and ghost cells: the groups of the distributed
/// mesh hold both). A cell in the groups of two entries, or of none, is an input error that
/// names the first such cell (the smallest Gmsh element tag over all ranks, each rank
/// checking its own cells) and their number. Collective.
fn cell_materials(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    model: fem::Model,
) -> Result<Materials, RunError> {
    let list: Vec<Material> = case
        .materials
        .iter()
        .map(|m| Material {
            young: m.young,
            poisson: m.poisson,
            model,
        })
        .collect();
    if let [only] = &case.materials[..] {
        if only.group.is_none() {
            return Ok(Materials::single(list[0]));
        }
    }
    const NONE: u16 = u16::MAX;
    let mut cell = vec![NONE; mesh.n_cells()];
    let n_own = mesh
        .global
        .as_ref()
        .map_or(mesh.n_cells(), |g| g.n_own_cells);
    // (tag, first entry, second entry) of the first own cell in two entries' groups
    let mut twice: Option<(u64, usize, usize)> = None;
    let mut n_twice = 0usize;
    for (i, m) in case.materials.iter().enumerate() {
        let name = m.group.as_deref().unwrap_or_default();
        for g in groups_named(mesh, name).filter(|g| g.dim == mesh.dim) {
            for &c in &g.elements {
                let had = cell[c];
                if had == NONE || had as usize == i {
                    cell[c] = i as u16;
                } else if c < n_own {
                    n_twice += 1;
                    let tag = mesh.cell_tags[c];
                    if twice.is_none_or(|t| tag < t.0) {
                        twice = Some((tag, had as usize, i));
                    }
                }
            }
        }
    }
    let first = ctx.min_u64(twice.map_or(u64::MAX, |t| t.0));
    let n_twice = ctx.sum_usize(n_twice);
    let local = match twice {
        Some((tag, i, j)) if tag == first => {
            let (a, b) = (&case.materials[i], &case.materials[j]);
            Err(case.error_at(
                &format!("{}.group", b.key),
                format!(
                    "the cell with Gmsh element tag {tag} ({n_twice} cell(s) in all) is in \
                     group \"{}\" of {} and in group \"{}\" of {}: a cell has one material",
                    a.group.as_deref().unwrap_or_default(),
                    a.key,
                    b.group.as_deref().unwrap_or_default(),
                    b.key
                ),
            ))
        }
        _ => Ok(()),
    };
    ctx.agree(local.map_err(RunError::from))?;
    let bare = (0..n_own).filter(|&c| cell[c] == NONE);
    let first = ctx.min_u64(
        bare.clone()
            .map(|c| mesh.cell_tags[c])
            .min()
            .unwrap_or(u64::MAX),
    );
    let n_bare = ctx.sum_usize(bare.count());
    if n_bare > 0 {
        // every rank has the numbers: all return the same error
        return Err(case
            .error_at(
                "material",
                format!(
                    "{n_bare} cell(s) of the mesh are in no [[material]] group (the first: Gmsh \
                     element tag {first}): every cell needs a material (add a [[material]] \
                     for their volume group)"
                ),
            )
            .into());
    }
    Ok(Materials::per_cell(list, cell))
}

/// The material whose modulus the single-modulus estimates use (the half-space model of the
/// contact predictor, the default Newton parameter c = 100 E h_c^(d−2)): of the materials of the
/// cells with a node on a contact group's facets, the stiffest (largest contact modulus
/// E / (1 − ν²), or E in plane stress); without contact cells, the stiffest of all. With one
/// material this is that material: single-material runs are unchanged. The materials at the
/// contact boundary, as both estimates are about its response; the stiffest of them, so that
/// the choice does not depend on the order of the entries and a stiff layer at the surface
/// is not estimated by a compliant one behind it. Collective (one sum).
fn reference_material(ctx: &Ctx, case: &Case, mesh: &Mesh, materials: &Materials) -> usize {
    let n = materials.list.len();
    if n == 1 {
        return 0;
    }
    let mut on_contact = vec![false; mesh.n_nodes()];
    for c in &case.contacts {
        for f in group_facets(mesh, &c.group) {
            for &v in mesh.facet(f) {
                on_contact[v] = true;
            }
        }
    }
    let n_own = mesh
        .global
        .as_ref()
        .map_or(mesh.n_cells(), |g| g.n_own_cells);
    let mut touched = vec![0.0; n];
    for c in 0..n_own {
        if mesh.cell(c).iter().any(|&v| on_contact[v]) {
            touched[materials.index(c)] = 1.0;
        }
    }
    let touched = ctx.sum_vec(&touched);
    let any = touched.iter().any(|&t| t > 0.0);
    let modulus = |i: usize| materials.list[i].contact_modulus();
    (0..n)
        .filter(|&i| !any || touched[i] > 0.0)
        .fold(None, |best: Option<usize>, i| match best {
            Some(b) if modulus(b) >= modulus(i) => Some(b),
            _ => Some(i),
        })
        .unwrap_or(0)
}

/// The half-space model's contact modulus where bodies touch each other: per body pair the
/// two sides in series, 1/E* = 1/E*_slave + 1/E*_master (Hertz' combined modulus), each side
/// the stiffest material of the cells at its group; the smallest of these and, with rigid
/// pairs too, the reference material's (a compliant estimate predicts the wider zone).
/// `None` without body pairs. Beside it the largest ratio of a pair's slave side to its master
/// side (the iterative preset's preconditioner pays for a stiff slave: solver.rs
/// `choose_preset`). Collective (one reduction).
fn pair_modulus(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    materials: &Materials,
) -> (Option<f64>, Option<f64>) {
    let pairs: Vec<(&str, &str)> = (case.contacts.iter())
        .filter_map(|c| match &c.obstacle {
            crate::case::ObstacleSpec::Body { group } => Some((c.group.as_str(), group.as_str())),
            _ => None,
        })
        .collect();
    if pairs.is_empty() {
        return (None, None);
    }
    let n_own = mesh
        .global
        .as_ref()
        .map_or(mesh.n_cells(), |g| g.n_own_cells);
    // the stiffest contact modulus of the owned cells with a node on the group's facets
    let stiffest = |group: &str| {
        let mut on = vec![false; mesh.n_nodes()];
        for f in group_facets(mesh, group) {
            for &v in mesh.facet(f) {
                on[v] = true;
            }
        }
        (0..n_own)
            .filter(|&c| mesh.cell(c).iter().any(|&v| on[v]))
            .map(|c| materials.of(c).contact_modulus())
            .fold(0.0f64, f64::max)
    };
    let mut mine = Vec::new();
    for (slave, master) in &pairs {
        mine.push(stiffest(slave));
        mine.push(stiffest(master));
    }
    let both: Vec<f64> = (ctx.all_gather_varcount(&mine).chunks_exact(mine.len()))
        .fold(vec![0.0; mine.len()], |acc, r| {
            acc.iter().zip(r).map(|(a, b)| a.max(*b)).collect()
        });
    let sides = (both.chunks_exact(2)).filter(|s| s[0] > 0.0 && s[1] > 0.0);
    let series = (sides.clone())
        .map(|s| 1.0 / (1.0 / s[0] + 1.0 / s[1]))
        .fold(f64::INFINITY, f64::min);
    let ratio = sides.map(|s| s[0] / s[1]).fold(0.0f64, f64::max);
    let rigid = case.contacts.len() > pairs.len();
    let reference = materials.reference_material().contact_modulus();
    let e = if rigid { series.min(reference) } else { series };
    (e.is_finite().then_some(e), (ratio > 0.0).then_some(ratio))
}

/// A body force given by expressions (`body_force.expr`) is finite at every quadrature point
/// of this rank's own cells (the points where assembly evaluates it): else an input error
/// naming the component and the point, of the faulty cell of smallest Gmsh tag on this rank
/// (that tag is the key for [`Ctx::agree_smallest`]). Local.
fn check_body_force(case: &Case, mesh: &Mesh) -> Option<(u64, InputError)> {
    let Some(BodyForceSpec::Expr(es)) = &case.body_force else {
        return None;
    };
    let dim = mesh.dim;
    let bad = std::cell::Cell::new(None);
    let probe = |p: [f64; 3]| {
        if bad.get().is_none() {
            if let Some(i) = es.iter().position(|e| !e.eval(p).is_finite()) {
                bad.set(Some((i, p)));
            }
        }
        [0.0; 3]
    };
    let n_own = mesh
        .global
        .as_ref()
        .map_or(mesh.n_cells(), |g| g.n_own_cells);
    let mut xs: Vec<[f64; 3]> = Vec::with_capacity(4);
    let mut out = [0.0; 12];
    // (tag, component, point) of the faulty cell of smallest tag
    let mut first: Option<(u64, usize, [f64; 3])> = None;
    for c in 0..n_own {
        let tag = mesh.cell_tags[c];
        if first.is_some_and(|f| f.0 < tag) {
            continue;
        }
        xs.clear();
        xs.extend(mesh.cell(c).iter().map(|&v| mesh.coords[v]));
        bad.set(None);
        fem::cell_load_quadrature(&xs, dim, &probe, &mut out[..xs.len() * dim]);
        if let Some((i, p)) = bad.get() {
            first = Some((tag, i, p));
        }
    }
    let (tag, i, p) = first?;
    Some((
        tag,
        case.error_at(
            &format!("body_force.expr[{i}]"),
            format!(
                "\"{}\" is not a finite number at {:?} (a quadrature point of cell {tag})",
                es[i].text(),
                &p[..dim],
            ),
        ),
    ))
}

/// All groups with this name (a name may label groups of several dimensions).
fn groups_named<'m>(mesh: &'m Mesh, name: &str) -> impl Iterator<Item = &'m mesh::Group> {
    let name = name.to_string();
    mesh.groups.iter().filter(move |g| g.name == name)
}

/// The facets (cells of dimension dim − 1) of every group with this name.
pub fn group_facets(mesh: &Mesh, name: &str) -> Vec<usize> {
    groups_named(mesh, name)
        .filter(|g| g.dim + 1 == mesh.dim)
        .flat_map(|g| g.elements.iter().copied())
        .collect()
}

/// The linear problem of a case (Dirichlet data per dof, loads).
pub fn problem<'m>(case: &Case, mesh: &'m Mesh, material: &'m Materials) -> Problem<'m> {
    let dim = mesh.dim;
    let mut fixed = vec![f64::NAN; mesh.n_nodes() * dim];
    let mut held_fixed = Vec::new();
    if case.dirichlet.iter().any(|d| !d.ramp) {
        held_fixed = vec![false; fixed.len()];
    }
    for d in &case.dirichlet {
        for g in groups_named(mesh, &d.group) {
            for v in mesh.group_nodes(g) {
                for (k, val) in d.value.iter().enumerate().take(dim) {
                    if let Some(x) = val {
                        fixed[v * dim + k] = *x;
                        if let Some(h) = held_fixed.get_mut(v * dim + k) {
                            *h = !d.ramp;
                        }
                    }
                }
            }
        }
    }
    let facet_loads = case
        .neumann
        .iter()
        .map(|n| FacetLoad {
            facets: group_facets(mesh, &n.group),
            kind: match &n.load {
                case::Load::Pressure(p) => FacetLoadKind::Pressure(*p),
                case::Load::Traction(t) => FacetLoadKind::Traction(vec3(t)),
            },
            ramp: n.ramp,
        })
        .collect();
    let body_force = match &case.body_force {
        Some(BodyForceSpec::Constant(f)) if f.iter().any(|&x| x != 0.0) => {
            BodyForce::Constant(vec3(f))
        }
        Some(BodyForceSpec::Expr(es)) => {
            let es = es.clone();
            BodyForce::Function(Box::new(move |p| {
                let mut f = [0.0; 3];
                for (v, e) in f.iter_mut().zip(&es) {
                    *v = e.eval(p);
                }
                f
            }))
        }
        _ => BodyForce::None,
    };
    Problem {
        mesh,
        material,
        fixed,
        held_fixed,
        facet_loads,
        body_force,
    }
}

/// One contact pair as the contact algorithm sees it (`[contact]` or one `[[contact]]` table).
#[derive(Clone)]
pub struct PairSettings {
    /// The pair's table in the case file (`contact` or `contact[i]`), named in messages.
    pub key: String,
    pub group: String,
    /// The obstacle as the case gives it (before any motion).
    pub obstacle: Obstacle,
    /// `motion`: the obstacle's rigid translation at load factor 1.
    pub motion: Option<case::Motion>,
    /// The obstacle's displacement d in the step being solved (t·m, or m when held; 0 without
    /// a motion): the contact condition is u_n + g0 − d·n ≥ 0 and friction acts on u_τ − d_τ
    /// (docs/obstacles.md, "Moving obstacles"). [`ContactSettings::at_factor`] sets it.
    pub displacement: [f64; 3],
    /// `force` (force control): the force at load factor 1.
    pub force: Option<case::Motion>,
    /// The force F of the step being solved (t·F, or F when held); 0 without force control.
    /// The obstacle's displacement is then δ·F/|F| with the approach δ solved for.
    pub force_now: [f64; 3],
    /// Tresca threshold g_R (1.44e) of the pair; 0 on a frictionless pair of a case with
    /// Tresca pairs (|λ_τ| ≤ 0: no tangential force), `None` in a case without Tresca.
    pub tresca_threshold: Option<f64>,
    /// Coulomb's μ of the pair; 0 on a frictionless pair and without Coulomb friction.
    pub coulomb_mu: f64,
}

impl PairSettings {
    /// `KEY.name`, a key of the pair's table.
    pub fn key(&self, name: &str) -> String {
        format!("{}.{name}", self.key)
    }
}

/// Everything the contact algorithm needs from the case, checked.
#[derive(Clone)]
pub struct ContactSettings {
    /// The case file (named in messages about the contact boundary).
    pub file: std::path::PathBuf,
    /// The contact pairs, in the order of the case file (at least one).
    pub pairs: Vec<PairSettings>,
    /// Tresca friction on some pair (Algorithm 2; the other pairs have threshold 0).
    pub tresca: bool,
    /// Coulomb friction: the coefficient μ of the first Coulomb pair (each node has its
    /// pair's, [`PairSettings::coulomb_mu`]) and the algorithm (one for all pairs); `None`
    /// otherwise.
    pub coulomb: Option<(f64, case::CoulombAlgorithm)>,
    pub rigid_modes: case::RigidModeHandling,
    pub newton: NewtonSection,
    /// Young's modulus (the default c = 100 E h_c^(d−2)): the reference material's
    /// ([`Materials::reference`]: with several materials, the stiffest at the contact).
    pub young: f64,
    /// The materials (the final certificate's reactions at the Dirichlet nodes).
    pub material: Materials,
    /// The contact modulus E* = E / (1 − ν²) (3D, plane strain) or E (plane stress) of the
    /// reference material, or with body pairs the two sides' in series (`pair_modulus`): the
    /// half-space predictor's (halfspace/).
    pub contact_modulus: f64,
    /// The rigid modes of the bodies that Dirichlet data leave free, and the body of every
    /// local node (the driver's body survey); `None`: the whole mesh is one body.
    pub modes: Option<std::sync::Arc<crate::mesh::BodyModes>>,
}

impl ContactSettings {
    /// True with a friction law: Algorithm 2 and its tangential states.
    pub fn friction(&self) -> bool {
        self.tresca || self.coulomb.is_some()
    }

    /// Moves every obstacle to where it is at load factor t ([`case::Motion::at`]).
    pub fn at_factor(&mut self, t: f64) {
        for p in &mut self.pairs {
            p.displacement = p.motion.as_ref().map_or([0.0; 3], |m| m.at(t));
            p.force_now = p.force.as_ref().map_or([0.0; 3], |m| m.at(t));
        }
    }

    /// True when every pair's motion and force change from factor `last` to `next` by `s`
    /// times their change from `before` to `last` (the load predictor's assumption, steps.rs):
    /// always for a ramped or held vector, not across a corner of a `table`.
    pub fn increments_parallel(&self, before: f64, last: f64, next: f64, s: f64) -> bool {
        self.pairs.iter().all(|p| {
            [&p.motion, &p.force].into_iter().flatten().all(|m| {
                if m.table.is_empty() {
                    return true;
                }
                let (b, l, n) = (m.at(before), m.at(last), m.at(next));
                let scale = (0..3)
                    .map(|k| (n[k] - l[k]).abs().max((l[k] - b[k]).abs()))
                    .fold(0.0, f64::max);
                (0..3).all(|k| ((n[k] - l[k]) - s * (l[k] - b[k])).abs() <= 1e-9 * scale)
            })
        })
    }

    /// The pairs under force control, with their indices, in pair order.
    pub fn force_pairs(&self) -> impl Iterator<Item = (usize, &PairSettings)> {
        self.pairs
            .iter()
            .enumerate()
            .filter(|(_, p)| p.force.is_some())
    }

    /// Each pair's obstacle displacement d of the step being solved.
    pub fn displacements(&self) -> Vec<[f64; 3]> {
        self.pairs.iter().map(|p| p.displacement).collect()
    }
}

/// The contact settings of a case (`contacts` non-empty).
pub fn contact_settings(
    case: &Case,
    contacts: &[ContactSection],
    materials: &Materials,
) -> Result<ContactSettings, InputError> {
    let dim = materials.model.dim();
    let tresca = contacts
        .iter()
        .any(|c| matches!(c.friction, Friction::Tresca { .. }));
    let pairs = contacts
        .iter()
        .map(|cc| {
            Ok(PairSettings {
                key: cc.key.clone(),
                group: cc.group.clone(),
                obstacle: obstacle_of(cc, dim, &case.file)?,
                motion: cc.motion.clone(),
                // a single static solve is the problem at factor 1
                displacement: cc.motion.as_ref().map_or([0.0; 3], |m| m.at(1.0)),
                force: cc.force.clone(),
                force_now: cc.force.as_ref().map_or([0.0; 3], |m| m.at(1.0)),
                tresca_threshold: match cc.friction {
                    Friction::Tresca { threshold } => Some(threshold),
                    Friction::None if tresca => Some(0.0),
                    Friction::None | Friction::Coulomb { .. } => None,
                },
                coulomb_mu: match cc.friction {
                    Friction::Coulomb { mu, .. } => mu,
                    Friction::None | Friction::Tresca { .. } => 0.0,
                },
            })
        })
        .collect::<Result<Vec<_>, InputError>>()?;
    Ok(ContactSettings {
        file: case.file.clone(),
        pairs,
        tresca,
        coulomb: contacts.iter().find_map(|c| match c.friction {
            Friction::Coulomb { mu, algorithm } => Some((mu, algorithm)),
            Friction::None | Friction::Tresca { .. } => None,
        }),
        rigid_modes: contacts[0].rigid_modes,
        newton: case.newton.clone(),
        young: materials.reference_material().young,
        material: materials.clone(),
        contact_modulus: (materials.half_space)
            .unwrap_or_else(|| materials.reference_material().contact_modulus()),
        modes: None,
    })
}

/// The obstacle of the case, checked (every shape: [`case::ObstacleSpec::to_obstacle`]).
pub fn obstacle_of(c: &ContactSection, dim: usize, file: &Path) -> Result<Obstacle, InputError> {
    c.obstacle
        .to_obstacle(dim)
        .map_err(|e| e.into_input_error(file, &format!("{}.obstacle", c.key)))
}
