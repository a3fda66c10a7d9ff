//! The driver: case → mesh → partition → assembly → solve → post-processing → output.
//! Used by the binary and by integration tests.

use crate::assembly::{self, BodyForce, FacetLoad, FacetLoadKind, Problem};
use crate::case::{self, vec3, Case, Field};
use crate::contact_report;
use crate::contact_set;
use crate::error::InputError;
use crate::fem::{self, Material};
use crate::mesh::{self, Mesh};
use crate::newton;
use crate::output;
use crate::partition::{self, Layout};
use crate::petsc::{self, PInt, Petsc, SolveInfo, Vector};
use crate::solver::{self, LinearSolver};
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a run failed.
#[derive(Debug)]
pub enum RunError {
    /// The user's input is wrong: one message, exit code 2, nothing written.
    Input(InputError),
    /// PETSc reported an error.
    Petsc(petsc::PetscError),
    /// Anything else (solver did not converge, output could not be written, ...).
    Failed(String),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Input(e) => write!(f, "{e}"),
            RunError::Petsc(e) => write!(f, "{e}"),
            RunError::Failed(s) => write!(f, "{s}"),
        }
    }
}

impl From<petsc::PetscError> for RunError {
    fn from(e: petsc::PetscError) -> Self {
        RunError::Petsc(e)
    }
}

impl From<InputError> for RunError {
    fn from(e: InputError) -> Self {
        RunError::Input(e)
    }
}

/// Rank-0 log line. Its arguments are evaluated on rank 0 only: never put a collective call in them.
#[macro_export]
macro_rules! say {
    ($ctx:expr, $($arg:tt)*) => {
        if $ctx.rank == 0 {
            println!($($arg)*);
        }
    };
}

/// The parallel context of a run.
pub struct Ctx<'a> {
    pub world: &'a SimpleCommunicator,
    pub petsc: &'a Petsc,
    pub rank: usize,
    pub size: usize,
}

impl<'a> Ctx<'a> {
    pub fn new(world: &'a SimpleCommunicator, petsc: &'a Petsc) -> Self {
        Ctx {
            world,
            petsc,
            rank: world.rank() as usize,
            size: world.size() as usize,
        }
    }

    /// True on every rank if it is true on any rank (one Allreduce).
    pub fn any(&self, flag: bool) -> bool {
        let mut out = 0i32;
        self.world
            .all_reduce_into(&(flag as i32), &mut out, SystemOperation::max());
        out != 0
    }

    pub fn sum_f64(&self, v: f64) -> f64 {
        let mut out = 0.0;
        self.world
            .all_reduce_into(&v, &mut out, SystemOperation::sum());
        out
    }

    pub fn max_f64(&self, v: f64) -> f64 {
        let mut out = 0.0;
        self.world
            .all_reduce_into(&v, &mut out, SystemOperation::max());
        out
    }

    /// One value per rank, on every rank.
    pub fn gather_f64(&self, v: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.size];
        self.world.all_gather_into(&v, &mut out[..]);
        out
    }
}

/// Peak resident memory of this process in bytes (VmHWM), 0 if unknown.
pub fn peak_memory_bytes() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map(|kb| kb * 1024.0)
        .unwrap_or(0.0)
}

/// Reads the mesh and checks the case against it (every rank does the same).
pub fn read_input(case: &Case) -> Result<(Mesh, Material), InputError> {
    let mesh = mesh::read_msh(&case.mesh.file)?;
    let groups: Vec<(String, usize)> = mesh
        .groups
        .iter()
        .map(|g| (g.name.clone(), g.dim))
        .collect();
    case.check_against_mesh(mesh.dim, &groups)?;
    case.check_facet_groups(&mesh)?;
    let model = match case.model(mesh.dim)? {
        case::Model::PlaneStrain => fem::Model::PlaneStrain,
        case::Model::PlaneStress => fem::Model::PlaneStress,
        case::Model::ThreeD => fem::Model::Solid,
    };
    let material = Material {
        young: case.material.young,
        poisson: case.material.poisson,
        model,
    };
    Ok((mesh, material))
}

/// All groups with this name (a name may label groups of several dimensions).
fn groups_named<'m>(mesh: &'m Mesh, name: &str) -> Vec<&'m mesh::Group> {
    mesh.groups.iter().filter(|g| g.name == name).collect()
}

/// The linear problem of a case (Dirichlet data per dof, loads).
pub fn problem_from_case<'m>(case: &Case, mesh: &'m Mesh, material: Material) -> Problem<'m> {
    let dim = mesh.dim;
    let mut fixed = vec![f64::NAN; mesh.n_nodes() * dim];
    for d in &case.dirichlet {
        for g in groups_named(mesh, &d.group) {
            for v in mesh.group_nodes(g) {
                for (k, val) in d.value.iter().enumerate().take(dim) {
                    if let Some(x) = val {
                        fixed[v * dim + k] = *x;
                    }
                }
            }
        }
    }
    let mut facet_loads = Vec::new();
    for n in &case.neumann {
        let facets: Vec<usize> = groups_named(mesh, &n.group)
            .into_iter()
            .filter(|g| g.dim + 1 == dim)
            .flat_map(|g| g.elements.iter().copied())
            .collect();
        let kind = match &n.load {
            case::Load::Pressure(p) => FacetLoadKind::Pressure(*p),
            case::Load::Traction(t) => FacetLoadKind::Traction(vec3(t)),
        };
        facet_loads.push(FacetLoad { facets, kind });
    }
    let body_force = match &case.body_force {
        Some(f) if f.iter().any(|&x| x != 0.0) => BodyForce::Constant(vec3(f)),
        _ => BodyForce::None,
    };
    Problem {
        mesh,
        material,
        fixed,
        facet_loads,
        body_force,
    }
}

/// Results of a solve that post-processing and output need.
pub struct Solution {
    /// Owned displacement values (owned nodes × dim, in global order).
    pub u_owned: Vec<f64>,
    pub u: Vector,
}

/// Timings of the phases, seconds.
#[derive(Default, Clone, Copy, Debug)]
pub struct Timings {
    pub read: f64,
    pub partition: f64,
    pub assembly: f64,
    pub solve: f64,
    pub post: f64,
    pub output: f64,
    pub total: f64,
}

/// Cell fields of the local cells (each `ncomp` values per local cell).
pub struct CellFields {
    pub stress: Option<Vec<f64>>,
    pub von_mises: Option<Vec<f64>>,
    pub von_mises_thesis: Option<Vec<f64>>,
    pub rank: Option<Vec<f64>>,
}

/// The values of a nodal vector (dim per node) at every node of this rank's cells, owned or
/// not: (sorted mesh node indices, dim values each). Collective.
pub fn local_cell_values(
    mesh: &Mesh,
    layout: &Layout,
    u: &Vector,
) -> petsc::Result<(Vec<usize>, Vec<f64>)> {
    let dim = mesh.dim;
    let mut nodes: Vec<usize> = layout
        .local_cells
        .iter()
        .flat_map(|&c| mesh.cell(c).iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let idx: Vec<PInt> = nodes
        .iter()
        .flat_map(|&v| (0..dim).map(move |k| (layout.node_global[v] * dim + k) as PInt))
        .collect();
    let vals = u.gather(&idx)?;
    Ok((nodes, vals))
}

/// Stresses and von Mises values of the local cells — only what `fields` asks for.
pub fn cell_fields(
    mesh: &Mesh,
    layout: &Layout,
    material: &Material,
    u: &Vector,
    out: &case::OutputSection,
) -> petsc::Result<CellFields> {
    let want_stress = out.wants(Field::Stress);
    let want_vm = out.wants(Field::VonMises);
    let want_vmt = out.wants(Field::VonMisesThesis);
    let dim = mesh.dim;
    let nlc = layout.local_cells.len();
    let mut f = CellFields {
        stress: None,
        von_mises: None,
        von_mises_thesis: None,
        rank: out
            .wants(Field::Rank)
            .then(|| vec![layout.rank as f64; nlc]),
    };
    if !(want_stress || want_vm || want_vmt) {
        // Every rank skips alike: output.fields is the same everywhere (no collective skipped).
        return Ok(f);
    }
    let (nodes, vals) = local_cell_values(mesh, layout, u)?;
    let mut stress = want_stress.then(|| Vec::with_capacity(nlc * 9));
    let mut vm = want_vm.then(|| Vec::with_capacity(nlc));
    let mut vmt = want_vmt.then(|| Vec::with_capacity(nlc));
    let mut x = [[0.0; 3]; 4];
    let mut ue = [0.0; 12];
    for &c in &layout.local_cells {
        let cn = mesh.cell(c);
        for (a, &v) in cn.iter().enumerate() {
            x[a] = mesh.coords[v];
            let p = nodes.binary_search(&v).expect("node gathered");
            ue[a * dim..(a + 1) * dim].copy_from_slice(&vals[p * dim..(p + 1) * dim]);
        }
        let s = fem::cell_stress(material, &x[..dim + 1], &ue[..(dim + 1) * dim]);
        if let Some(st) = stress.as_mut() {
            st.extend(s.iter().flatten());
        }
        if let Some(v) = vm.as_mut() {
            v.push(fem::von_mises(&s));
        }
        if let Some(v) = vmt.as_mut() {
            v.push(fem::von_mises_thesis(&s, dim));
        }
    }
    f.stress = stress;
    f.von_mises = vm;
    f.von_mises_thesis = vmt;
    Ok(f)
}

/// A staging directory next to `dir`, renamed into place when everything is written.
pub fn staging_dir(dir: &Path) -> PathBuf {
    let name = dir
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = dir.parent().unwrap_or(Path::new("."));
    parent.join(format!(".{name}.partial"))
}

/// Moves every file of `staging` into `dir` (each rename atomic), then removes `staging`.
pub fn commit_staging(staging: &Path, dir: &Path) -> std::io::Result<()> {
    if !dir.exists() {
        return std::fs::rename(staging, dir);
    }
    for entry in std::fs::read_dir(staging)? {
        let entry = entry?;
        std::fs::rename(entry.path(), dir.join(entry.file_name()))?;
    }
    std::fs::remove_dir(staging)
}

/// Contact results to write.
pub struct ContactOutput {
    pub fields: contact_report::ContactFields,
    pub n_global: usize,
    pub offset: usize,
    pub csv: String,
}

fn linear_json(case: &Case, report: &LinearReport) -> Value {
    json!({ "linear_solver": {
        "preset": case.solver.preset.name(),
        "ksp_type": report.ksp_type, "pc_type": report.pc_type,
        "iterations": report.solve.iterations,
        "converged_reason": report.solve.reason_name,
        "converged_reason_code": report.solve.reason,
    }})
}

/// Everything about a linear run that the summary reports.
pub struct LinearReport {
    pub solve: SolveInfo,
    pub ksp_type: String,
    pub pc_type: String,
}

/// Configures the linear solver from the options database (preset < case < command line)
/// and solves A u = b once.
pub fn linear_solve(
    ctx: &Ctx,
    mesh: &Mesh,
    layout: &Layout,
    sys: &mut assembly::System,
    settings: &case::SolverSection,
) -> Result<(Vector, LinearReport), RunError> {
    let comm = ctx.petsc.comm();
    let t = Instant::now();
    solver::configure(
        settings.preset,
        settings.rtol,
        true,
        &settings.petsc_options,
    )?;
    let coords = match settings.preset {
        case::Preset::Iterative => Some(assembly::coordinate_vector(comm, mesh, layout)?),
        case::Preset::Direct => None,
    };
    let mut ls = LinearSolver::new(comm, &mut sys.a, coords.as_ref())?;
    let mut u = sys.b.duplicate()?;
    let info = ls.solve(&sys.b, &mut u)?;
    let secs = t.elapsed().as_secs_f64();
    let (ksp_type, pc_type) = ls.ksp.type_names()?;
    say!(
        ctx,
        "solve: {secs:.3} s, {ksp_type}/{pc_type}, {} iterations, {}",
        info.iterations,
        info.reason_name
    );
    if !info.converged() {
        return Err(RunError::Failed(format!(
            "the linear solver did not converge: {} after {} iterations ({ksp_type}/{pc_type})",
            info.reason_name, info.iterations
        )));
    }
    Ok((
        u,
        LinearReport {
            solve: info,
            ksp_type,
            pc_type,
        },
    ))
}

/// Runs a whole case. Returns the summary JSON (rank 0's copy is complete).
pub fn run_case(ctx: &Ctx, case: &Case) -> Result<Value, RunError> {
    let t_total = Instant::now();
    let mut tm = Timings::default();
    let comm = ctx.petsc.comm();

    // Input: every rank reads the case and the mesh; all agree before anything collective.
    let t = Instant::now();
    let input = read_input(case);
    if ctx.any(input.is_err()) {
        return Err(match input {
            Err(e) => RunError::Input(e),
            Ok(_) => RunError::Failed("input rejected on another rank".into()),
        });
    }
    let (mesh, material) = input.expect("checked above");
    tm.read = t.elapsed().as_secs_f64();
    let dim = mesh.dim;
    say!(
        ctx,
        "mesh {}: {}D, {} nodes, {} cells, {} boundary facets, groups: {}",
        case.mesh.file.display(),
        dim,
        mesh.n_nodes(),
        mesh.n_cells(),
        mesh.facets.len() / dim.max(1),
        mesh.groups
            .iter()
            .map(|g| format!("{} ({}D, {})", g.name, g.dim, g.elements.len()))
            .collect::<Vec<_>>()
            .join(", ")
    );

    let t = Instant::now();
    let layout = partition::partition(ctx.world, comm, &mesh, "ptscotch")?;
    tm.partition = t.elapsed().as_secs_f64();
    let cpr = layout.cells_per_rank();
    let npr = layout.nodes_per_rank();
    let imbalance = |v: &[usize]| {
        let max = *v.iter().max().unwrap_or(&0) as f64;
        let mean = v.iter().sum::<usize>() as f64 / v.len().max(1) as f64;
        if mean > 0.0 {
            max / mean
        } else {
            1.0
        }
    };
    say!(
        ctx,
        "partition: {} ranks, cells per rank {:?} (max/mean {:.3}), nodes per rank {:?}",
        ctx.size,
        cpr,
        imbalance(&cpr),
        npr
    );
    let n_dofs = mesh.n_nodes() * dim;
    say!(ctx, "dofs: {n_dofs}");

    let t = Instant::now();
    let problem = problem_from_case(case, &mesh, material);
    let mut sys = assembly::assemble(comm, &layout, &problem)?;
    tm.assembly = t.elapsed().as_secs_f64();
    let mallocs = ctx.sum_f64(sys.stats.mallocs);
    let matrix_seconds = ctx.max_f64(sys.stats.matrix_seconds);
    let nonzeros = ctx.sum_f64(sys.stats.nonzeros);
    say!(
        ctx,
        "assembly: {:.3} s (matrix {:.3} s, {} nonzeros, {} mallocs)",
        tm.assembly,
        matrix_seconds,
        nonzeros,
        mallocs
    );
    if mallocs > 0.0 {
        return Err(RunError::Failed(format!(
            "assembly needed {mallocs} mallocs: the preallocation is wrong (a bug)"
        )));
    }

    let t = Instant::now();
    let mut contact_out: Option<ContactOutput> = None;
    let (u, report_json) = match &case.contact {
        None => {
            let (u, report) = linear_solve(ctx, &mesh, &layout, &mut sys, &case.solver)?;
            (u, linear_json(case, &report))
        }
        Some(cc) => {
            let cs = contact_set::build(ctx.world, &mesh, &layout, cc, &problem.fixed, &case.file);
            if ctx.any(cs.is_err()) {
                return Err(match cs {
                    Err(e) => RunError::Input(e),
                    Ok(_) => RunError::Failed("contact set rejected on another rank".into()),
                });
            }
            let cs = cs.expect("checked");
            say!(
                ctx,
                "contact: {} nodes on '{}'{}",
                cs.n_global,
                cc.group,
                if cs.excluded_dirichlet > 0 {
                    format!(
                        " ({} more left to their Dirichlet data)",
                        cs.excluded_dirichlet
                    )
                } else {
                    String::new()
                }
            );
            let tresca = matches!(cc.friction, case::Friction::Tresca { .. });
            solver::configure(
                case.solver.preset,
                case.solver.rtol,
                !tresca,
                &case.solver.petsc_options,
            )?;
            let coords = match case.solver.preset {
                case::Preset::Iterative => Some(assembly::coordinate_vector(comm, &mesh, &layout)?),
                case::Preset::Direct => None,
            };
            let nr = newton::semismooth_newton(
                ctx,
                &mesh,
                &layout,
                &mut sys,
                &problem.fixed,
                &cs,
                &case.newton,
                cc.rigid_modes,
                coords.as_ref(),
                tresca,
                material.young,
            )?;
            if !nr.converged {
                return Err(RunError::Failed(format!(
                    "Newton did not converge in newton.max_steps = {} steps (active set still \
                     changing: {} node(s) in the last step)",
                    case.newton.max_steps,
                    nr.history.last().map(|h| h.changed).unwrap_or(0)
                )));
            }
            let table = contact_report::gather(ctx, &cs, &nr.nodes, dim);
            let total_force = contact_report::total_force(ctx, &nr.nodes);
            let half_width = table.half_width(&cs.obstacle);
            let kkt = table.kkt(!tresca);
            // The final state against (3.14): violations beyond 1e-8 of the problem's own
            // scales are reported (they mean an inexact linear solve, not round-off).
            {
                let f = |k: &str| kkt[k].as_f64().unwrap_or(0.0);
                let (fs, ls) = (f("force_scale"), f("length_scale"));
                let bad = f("max_penetration") > 1e-8 * ls
                    || f("max_positive_lambda_n") > 1e-8 * fs
                    || f("max_complementarity") > 1e-8 * fs * ls
                    || (!tresca && f("max_abs_lambda_t") > 1e-8 * fs);
                if bad {
                    say!(
                        ctx,
                        "warning: the final state violates (3.14) beyond round-off: {kkt}"
                    );
                }
            }
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
            let newton_json = json!({
                "algorithm": if tresca { 2 } else { 1 },
                "init": case.newton.init.name(),
                "c": nr.c,
                "c_default": case.newton.c.is_none(),
                "steps": nr.steps,
                "converged": nr.converged,
                "history": nr.history,
                "rows_seconds": nr.rows_seconds,
                "lambda_seconds": nr.lambda_seconds,
                "pinned_dofs": nr.pinned_final.len(),
                "on_cycle": case.newton.on_cycle.name(),
                "cycle_detected_at": nr.cycle_detected_at,
            });
            let contact_json = json!({
                "nodes": cs.n_global,
                "excluded_dirichlet": cs.excluded_dirichlet,
                "active_count": table.active_count(),
                "max_pressure": table.max_pressure(),
                "total_force": &total_force[..dim],
                "half_width": half_width,
                "kkt": kkt,
            });
            let mut contact_json = contact_json;
            if tresca {
                contact_json["friction"] = table.friction_certificate();
            }
            let fields = contact_report::fields(&cs, &nr.nodes, dim, tresca);
            contact_out = Some(ContactOutput {
                fields,
                n_global: cs.n_global,
                offset: cs.offset,
                csv: table.csv(),
            });
            (
                nr.u,
                json!({ "newton": newton_json, "contact": contact_json,
                        "linear_solver": { "preset": case.solver.preset.name() } }),
            )
        }
    };
    tm.solve = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let cells = cell_fields(&mesh, &layout, &material, &u, &case.output)?;
    tm.post = t.elapsed().as_secs_f64();

    let summary_wo_output = |tm: &Timings, mem: &[f64]| {
        let mut v = json!({
            "case": case.file.display().to_string(),
            "mesh": case.mesh.file.display().to_string(),
            "dimension": dim,
            "model": format!("{:?}", material.model),
            "cells": mesh.n_cells(),
            "nodes": mesh.n_nodes(),
            "dofs": n_dofs,
            "ranks": ctx.size,
            "partition": { "cells_per_rank": cpr, "nodes_per_rank": npr,
                           "cell_imbalance": imbalance(&cpr) },
            "assembly": { "mallocs": mallocs, "matrix_seconds_max": matrix_seconds },
            "timings": { "read": tm.read, "partition": tm.partition, "assembly": tm.assembly,
                         "solve": tm.solve, "post": tm.post, "output": tm.output,
                         "total": tm.total },
            "peak_memory_bytes_per_rank": mem,
        });
        if let (Value::Object(a), Value::Object(b)) = (&mut v, &report_json) {
            for (k, x) in b {
                a.insert(k.clone(), x.clone());
            }
        }
        v
    };
    write_output(
        ctx,
        case,
        &mesh,
        &layout,
        &u,
        &cells,
        contact_out.as_ref(),
        |tm_out| {
            let mut tm2 = tm;
            tm2.output = tm_out;
            tm2.total = t_total.elapsed().as_secs_f64();
            let mem = ctx.gather_f64(peak_memory_bytes());
            say!(
                ctx,
                "timings [s]: read {:.3}, partition {:.3}, assembly {:.3}, solve {:.3}, post {:.3}, \
                 output {:.3}, total {:.3}; peak memory per rank {:.0} MB (max)",
                tm2.read,
                tm2.partition,
                tm2.assembly,
                tm2.solve,
                tm2.post,
                tm2.output,
                tm2.total,
                mem.iter().fold(0.0f64, |a, &b| a.max(b)) / 1e6
            );
            summary_wo_output(&tm2, &mem)
        },
    )
}

/// Writes solution.xdmf/.h5 and summary.json into a staging directory and moves them into
/// place. `summary` is called (collectively) once the heavy output is written.
#[allow(clippy::too_many_arguments)]
fn write_output(
    ctx: &Ctx,
    case: &Case,
    mesh: &Mesh,
    layout: &Layout,
    u: &Vector,
    cells: &CellFields,
    contact: Option<&ContactOutput>,
    summary: impl FnOnce(f64) -> Value,
) -> Result<Value, RunError> {
    let t = Instant::now();
    let dim = mesh.dim;
    let dir = case.output.dir.clone();
    let staging = staging_dir(&dir);
    let mut err = None;
    if ctx.rank == 0 {
        let _ = std::fs::remove_dir_all(&staging);
        if let Err(e) = std::fs::create_dir_all(&staging) {
            err = Some(format!("cannot create {}: {e}", staging.display()));
        }
    }
    if ctx.any(err.is_some()) {
        return Err(RunError::Failed(
            err.unwrap_or_else(|| "output directory could not be created".into()),
        ));
    }
    let coords: Vec<[f64; 3]> = layout.owned_nodes.iter().map(|&v| mesh.coords[v]).collect();
    let node_ids: Vec<u64> = layout
        .owned_nodes
        .iter()
        .map(|&v| mesh.node_tags[v])
        .collect();
    let connectivity: Vec<usize> = layout
        .local_cells
        .iter()
        .flat_map(|&c| mesh.cell(c).iter().map(|&v| layout.node_global[v]))
        .collect();
    let cell_ids: Vec<u64> = layout
        .local_cells
        .iter()
        .map(|&c| mesh.cell_tags[c])
        .collect();
    let disp: Option<Vec<f64>> = if case.output.wants(Field::Displacement) {
        let uo = u.to_local_vec()?;
        Some(
            uo.chunks_exact(dim)
                .flat_map(|c| (0..3).map(move |k| if k < dim { c[k] } else { 0.0 }))
                .collect(),
        )
    } else {
        None
    };
    let mut nodal = Vec::new();
    if let Some(d) = &disp {
        nodal.push(output::Field {
            name: "displacement",
            ncomp: 3,
            data: d,
        });
    }
    let mut cellwise = Vec::new();
    if let Some(s) = &cells.stress {
        cellwise.push(output::Field {
            name: "stress",
            ncomp: 9,
            data: s,
        });
    }
    if let Some(s) = &cells.von_mises {
        cellwise.push(output::Field {
            name: "von_mises",
            ncomp: 1,
            data: s,
        });
    }
    if let Some(s) = &cells.von_mises_thesis {
        cellwise.push(output::Field {
            name: "von_mises_thesis",
            ncomp: 1,
            data: s,
        });
    }
    if let Some(s) = &cells.rank {
        cellwise.push(output::Field {
            name: "rank",
            ncomp: 1,
            data: s,
        });
    }
    let (nlo, _) = layout.node_range();
    let piece = output::Piece {
        dim,
        n_nodes_global: mesh.n_nodes(),
        node_offset: nlo,
        coords: &coords,
        node_ids: &node_ids,
        n_cells_global: mesh.n_cells(),
        cell_offset: layout.cell_offsets[layout.rank],
        connectivity: &connectivity,
        cell_ids: &cell_ids,
        nodal,
        cellwise,
        contact: contact
            .filter(|_| case.output.wants(Field::Contact))
            .map(|c| output::ContactPiece {
                n_global: c.n_global,
                offset: c.offset,
                coords: &c.fields.coords,
                node_ids: &c.fields.node_ids,
                fields: c
                    .fields
                    .fields
                    .iter()
                    .map(|(name, ncomp, data)| output::Field {
                        name,
                        ncomp: *ncomp,
                        data,
                    })
                    .collect(),
            }),
    };
    let r = output::write_xdmf_hdf5(ctx.world, &staging, &piece);
    if ctx.any(r.is_err()) {
        if ctx.rank == 0 {
            let _ = std::fs::remove_dir_all(&staging);
        }
        return Err(RunError::Failed(
            r.err()
                .unwrap_or_else(|| "output failed on another rank".into()),
        ));
    }
    let t_out = t.elapsed().as_secs_f64();
    let summary = summary(t_out);
    let mut err = None;
    if ctx.rank == 0 {
        let text = serde_json::to_string_pretty(&summary).expect("JSON");
        let res = std::fs::write(staging.join("summary.json"), text + "\n")
            .and_then(|_| match contact {
                Some(c) => std::fs::write(staging.join("contact_nodes.csv"), &c.csv),
                None => Ok(()),
            })
            .and_then(|_| {
                if let Some(p) = dir.parent() {
                    std::fs::create_dir_all(p)?;
                }
                commit_staging(&staging, &dir)
            });
        if let Err(e) = res {
            let _ = std::fs::remove_dir_all(&staging);
            err = Some(format!("cannot write results to {}: {e}", dir.display()));
        }
    }
    if ctx.any(err.is_some()) {
        return Err(RunError::Failed(
            err.unwrap_or_else(|| "output failed on rank 0".into()),
        ));
    }
    say!(
        ctx,
        "output: {} ({:.3} s)",
        dir.join("solution.xdmf").display(),
        t_out
    );
    Ok(summary)
}
