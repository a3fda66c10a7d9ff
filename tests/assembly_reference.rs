//! The assembled A and f against references written out here, on 1 and 2 ranks, 2D and 3D:
//!
//! * A x for a smooth vector x against an element-by-element evaluation (each cell's
//!   Voigt BᵀDB with engineering constants, Dirichlet rows/columns dropped except the
//!   diagonal), no sparse matrix involved;
//! * f: body force f·|T|/(d+1) per cell node minus Σ K_ij g_j over fixed j; A_jj g_j on
//!   fixed dofs;
//! * the energy uᵀ A u of a linear field u = B x without Dirichlet data equals
//!   |Ω| (λ tr(ε)² + 2μ ε:ε) exactly (P1 reproduces linear fields).
//!
//! The test starts its own executable under mpirun: the `#[ignore]`d `worker` test does the
//! MPI work and prints one `ASMREF {json}` line per mesh on rank 0.

// Index loops mirror the tensor formulas.
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use std::time::Duration;

use mpi::traits::*;
use signorini_mpi::assembly::{self, BodyForce, Problem};
use signorini_mpi::fem::{Material, Materials, Model};
use signorini_mpi::mesh::{self, Mesh};
use signorini_mpi::partition::{self, Layout};
use signorini_mpi::petsc::{MPI_Comm, Petsc, Vector};

const WORKER_ENV: &str = "SIGNORINI_ASSEMBLY_REFERENCE_WORKER";

/// (lambda, mu) of the model, written out independently of the library.
fn lame(young: f64, nu: f64, model: Model) -> (f64, f64) {
    let mu = young / (2.0 * (1.0 + nu));
    let lambda = match model {
        Model::PlaneStress => young * nu / (1.0 - nu * nu),
        _ => young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
    };
    (lambda, mu)
}

/// Element stiffness (row-major nd × nd) as Voigt BᵀDB: gradients from the inverse of the
/// Jacobian (solved by Cramer's rule), D from (lambda, mu).
fn reference_element(x: &[[f64; 3]], dim: usize, lambda: f64, mu: f64) -> (Vec<f64>, f64) {
    let n = dim + 1;
    // J = [x1-x0, x2-x0(, x3-x0)] columns; grad phi_k (k >= 1) = rows of J^{-1}.
    let mut j = [[0.0; 3]; 3];
    for c in 0..dim {
        for r in 0..dim {
            j[r][c] = x[c + 1][r] - x[0][r];
        }
    }
    let (inv, det) = if dim == 2 {
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let inv = [
            [j[1][1] / det, -j[0][1] / det, 0.0],
            [-j[1][0] / det, j[0][0] / det, 0.0],
            [0.0; 3],
        ];
        (inv, det)
    } else {
        let m = j;
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        let mut inv = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                // cofactor of m[c][r] / det
                let (r1, r2) = ((c + 1) % 3, (c + 2) % 3);
                let (c1, c2) = ((r + 1) % 3, (r + 2) % 3);
                inv[r][c] = (m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]) / det;
            }
        }
        (inv, det)
    };
    let measure = if dim == 2 {
        det.abs() / 2.0
    } else {
        det.abs() / 6.0
    };
    let mut g = vec![[0.0; 3]; n];
    for k in 1..n {
        g[k] = inv[k - 1];
        for i in 0..dim {
            g[0][i] -= inv[k - 1][i];
        }
    }
    // Voigt B (nv × nd) and D (nv × nv).
    let nd = n * dim;
    let nv = if dim == 2 { 3 } else { 6 };
    let mut b = vec![0.0; nv * nd];
    let mut d = vec![0.0; nv * nv];
    let shear: &[(usize, usize)] = if dim == 2 {
        &[(0, 1)]
    } else {
        &[(1, 2), (0, 2), (0, 1)]
    };
    for a in 0..n {
        for i in 0..dim {
            b[i * nd + a * dim + i] = g[a][i];
        }
        for (s, &(p, q)) in shear.iter().enumerate() {
            b[(dim + s) * nd + a * dim + p] = g[a][q];
            b[(dim + s) * nd + a * dim + q] = g[a][p];
        }
    }
    for i in 0..dim {
        for k in 0..dim {
            d[i * nv + k] = lambda;
        }
        d[i * nv + i] += 2.0 * mu;
    }
    for s in dim..nv {
        d[s * nv + s] = mu;
    }
    let mut k = vec![0.0; nd * nd];
    for r in 0..nd {
        for c in 0..nd {
            let mut s = 0.0;
            for p in 0..nv {
                for q in 0..nv {
                    s += b[p * nd + r] * d[p * nv + q] * b[q * nd + c];
                }
            }
            k[r * nd + c] = measure * s;
        }
    }
    (k, measure)
}

fn smooth(i: usize) -> f64 {
    (1.3 * i as f64 + 0.7).sin() + 0.25 * (0.37 * i as f64).cos()
}

/// The energy uᵀ A u of a linear field u (no Dirichlet data: A of the whole mesh) and its exact
/// value, the volume times λ tr(ε)² + 2μ ε:ε. Collective.
fn linear_field_energy(
    world: &mpi::topology::SimpleCommunicator,
    comm: MPI_Comm,
    (mesh, layout): (&Mesh, &Layout),
    material: Material,
    (lambda, mu): (f64, f64),
) -> (f64, f64) {
    let (dim, n_owned) = (mesh.dim, layout.n_owned_nodes());
    // Energy of a linear field, no Dirichlet data.
    let bm = [[0.3, -0.2, 0.15], [0.1, 0.25, -0.05], [-0.12, 0.07, 0.2]];
    let free = Problem {
        mesh,
        held_fixed: Vec::new(),
        material: &Materials::single(material),
        fixed: vec![f64::NAN; mesh.n_nodes() * dim],
        facet_loads: vec![],
        body_force: BodyForce::None,
    };
    let sys2 = assembly::assemble(comm, layout, &free).expect("assembly");
    let mut u = Vector::new_mpi(comm, n_owned * dim, dim).unwrap();
    u.write(|us| {
        for (l, &v) in layout.owned_nodes.iter().enumerate() {
            let p = mesh.coords[v];
            for i in 0..dim {
                us[l * dim + i] = (0..dim).map(|j| bm[i][j] * p[j]).sum::<f64>() + 0.1;
            }
        }
    })
    .unwrap();
    let mut au = u.duplicate().unwrap();
    sys2.a.mult(&u, &mut au).unwrap();
    let (uv, auv) = (u.to_local_vec().unwrap(), au.to_local_vec().unwrap());
    let local: f64 = uv.iter().zip(&auv).map(|(a, b)| a * b).sum();
    let mut energy = 0.0;
    world.all_reduce_into(&local, &mut energy, mpi::collective::SystemOperation::sum());
    let volume: f64 = (0..mesh.n_cells())
        .map(|c| mesh.cell_measure(c).abs())
        .sum();
    let mut eps = [[0.0; 3]; 3];
    for i in 0..dim {
        for j in 0..dim {
            eps[i][j] = 0.5 * (bm[i][j] + bm[j][i]);
        }
    }
    let tr: f64 = (0..dim).map(|i| eps[i][i]).sum();
    let ee: f64 = (0..dim)
        .flat_map(|i| (0..dim).map(move |j| (i, j)))
        .map(|(i, j)| eps[i][j] * eps[i][j])
        .sum();
    let exact = volume * (lambda * tr * tr + 2.0 * mu * ee);

    (energy, exact)
}

/// Runs the checks on one mesh; returns the JSON line (rank 0 prints it).
fn check_mesh(world: &mpi::topology::SimpleCommunicator, petsc: &Petsc, path: &str) -> String {
    let mesh: Mesh = mesh::read_msh(std::path::Path::new(path)).expect("test mesh");
    let dim = mesh.dim;
    let model = if dim == 2 {
        Model::PlaneStrain
    } else {
        Model::Solid
    };
    let material = Material {
        young: 3.0,
        poisson: 0.3,
        model,
    };
    let (lambda, mu) = lame(3.0, 0.3, model);
    let comm = petsc.comm();
    let layout = partition::partition(world, comm, &mesh, "ptscotch").expect("partition");
    let (lo, _) = layout.node_range();
    let n_owned = layout.n_owned_nodes();

    // Dirichlet data: every dof of the nodes with x < 0.3 fixed to a smooth nonzero value,
    // and the y component of the nodes with y > 0.7.
    let mut fixed = vec![f64::NAN; mesh.n_nodes() * dim];
    for (v, x) in mesh.coords.iter().enumerate() {
        for i in 0..dim {
            if x[0] < 0.3 || (i == 1 && x[1] > 0.7) {
                fixed[v * dim + i] = 0.01 * smooth(v * dim + i + 5);
            }
        }
    }
    let force = [0.3, -0.2, 0.1];
    let problem = Problem {
        mesh: &mesh,
        held_fixed: Vec::new(),
        material: &Materials::single(material),
        fixed: fixed.clone(),
        facet_loads: vec![],
        body_force: BodyForce::Constant(force),
    };
    let sys = assembly::assemble(comm, &layout, &problem).expect("assembly");

    // Reference A x and f over every cell of the mesh (each rank its owned rows).
    let nd = (dim + 1) * dim;
    let xval = |v: usize, i: usize| smooth(layout.node_global[v] * dim + i);
    let mut y_ref = vec![0.0; mesh.n_nodes() * dim];
    let mut f_ref = vec![0.0; mesh.n_nodes() * dim];
    let mut diag = vec![0.0; mesh.n_nodes() * dim];
    for c in 0..mesh.n_cells() {
        let nodes = mesh.cell(c);
        let xs: Vec<[f64; 3]> = nodes.iter().map(|&v| mesh.coords[v]).collect();
        let (k, measure) = reference_element(&xs, dim, lambda, mu);
        let dof = |l: usize| nodes[l / dim] * dim + l % dim;
        for r in 0..nd {
            let gr = dof(r);
            f_ref[gr] += force[r % dim] * measure / (dim + 1) as f64;
            for cc in 0..nd {
                let gc = dof(cc);
                let kv = k[r * nd + cc];
                if r == cc {
                    diag[gr] += kv;
                }
                let (fr, fc) = (!fixed[gr].is_nan(), !fixed[gc].is_nan());
                if fr || fc {
                    if r == cc {
                        y_ref[gr] += kv * xval(nodes[cc / dim], cc % dim);
                    } else if !fr {
                        f_ref[gr] -= kv * fixed[gc];
                    }
                    continue;
                }
                y_ref[gr] += kv * xval(nodes[cc / dim], cc % dim);
            }
        }
    }
    let mut x = Vector::new_mpi(comm, n_owned * dim, dim).unwrap();
    x.write(|xs| {
        for (l, &v) in layout.owned_nodes.iter().enumerate() {
            for i in 0..dim {
                xs[l * dim + i] = xval(v, i);
            }
        }
    })
    .unwrap();
    let mut y = x.duplicate().unwrap();
    sys.a.mult(&x, &mut y).unwrap();
    let y = y.to_local_vec().unwrap();
    let b = sys.b.to_local_vec().unwrap();
    let (mut err_ax, mut scale_ax, mut err_f, mut scale_f) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (l, &v) in layout.owned_nodes.iter().enumerate() {
        assert_eq!(layout.node_global[v], lo + l);
        for i in 0..dim {
            let g = v * dim + i;
            err_ax = err_ax.max((y[l * dim + i] - y_ref[g]).abs());
            scale_ax = scale_ax.max(y_ref[g].abs());
            let fr = if fixed[g].is_nan() {
                f_ref[g]
            } else {
                diag[g] * fixed[g]
            };
            err_f = err_f.max((b[l * dim + i] - fr).abs());
            scale_f = scale_f.max(fr.abs());
        }
    }

    let (energy, exact) =
        linear_field_energy(world, comm, (&mesh, &layout), material, (lambda, mu));

    // Largest errors over the ranks.
    let mut errs = [err_ax / scale_ax, err_f / scale_f];
    let local_errs = errs;
    world.all_reduce_into(
        &local_errs[..],
        &mut errs[..],
        mpi::collective::SystemOperation::max(),
    );
    serde_json::json!({
        "mesh": path,
        "ranks": world.size(),
        "ax_rel_err": errs[0],
        "f_rel_err": errs[1],
        "energy": energy,
        "energy_exact": exact,
        "fixed_dofs": fixed.iter().filter(|g| !g.is_nan()).count(),
    })
    .to_string()
}

#[test]
#[ignore = "run under mpirun by assembly_matches_references"]
fn worker() {
    let Ok(meshes) = std::env::var(WORKER_ENV) else {
        return;
    };
    let universe = mpi::initialize().expect("MPI");
    let world = universe.world();
    let petsc = Petsc::init(&[]).expect("PETSc");
    for m in meshes.split(',') {
        let line = check_mesh(&world, &petsc, m);
        if world.rank() == 0 {
            println!("\nASMREF {line}");
        }
    }
    drop(petsc);
}

#[test]
fn assembly_matches_references() {
    let dir = env!("CARGO_MANIFEST_DIR");
    let meshes = [
        format!("{dir}/tests/meshes/square_h0.25.msh"),
        format!("{dir}/tests/meshes/cube_h0.25.msh"),
    ];
    let exe = std::env::current_exe().expect("test executable");
    for np in [1, 2] {
        let args: Vec<String> = ["worker", "--exact", "--ignored", "--nocapture"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let mut cmd = mpirun(np, &exe, &args);
        cmd.env(WORKER_ENV, meshes.join(","));
        let r = run_with_timeout(cmd, Duration::from_secs(180));
        r.expect_code(0, &format!("assembly reference worker on {np} ranks"));
        let rows = json_lines(&r.stdout, "ASMREF ");
        assert_eq!(rows.len(), meshes.len(), "one line per mesh:\n{}", r.stdout);
        for row in rows {
            let f = |k: &str| row[k].as_f64().unwrap_or_else(|| panic!("{k}: {row}"));
            assert_eq!(row["ranks"].as_u64(), Some(np as u64), "{row}");
            assert!(f("fixed_dofs") > 10.0, "too few fixed dofs to test: {row}");
            assert!(
                f("ax_rel_err") <= 1e-12,
                "A x differs from the reference: {row}"
            );
            assert!(
                f("f_rel_err") <= 1e-12,
                "f differs from the reference: {row}"
            );
            let (e, ex) = (f("energy"), f("energy_exact"));
            assert!(ex > 0.0, "{row}");
            assert!(
                (e - ex).abs() <= 1e-12 * ex,
                "energy of a linear field: {e} vs exact {ex}: {row}"
            );
        }
    }
}
