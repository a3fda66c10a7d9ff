//! The condensed path's MUMPS phases on a matrix whose every entry has the same bits on any
//! rank count, run under mpirun by tests/determinism.rs (issue 51).
//!
//! ```text
//! mpirun -n 3 target/release/examples/schur_repeat N [one_process]
//! ```
//!
//! The matrix: the 5-point Laplacian of an N × N grid plus 0.01 on the diagonal (symmetric
//! positive definite; entries written, never summed), rows in contiguous blocks per rank. The
//! Schur variables: the grid's middle row (N unknowns, the "contact line"). The elimination
//! order: Scotch's nested dissection of the grid's graph on rank 0 (sequential, fixed seed:
//! the same order whatever the rank count), the Schur variables last. Then MUMPS' analysis,
//! factorisation with the Schur complement S, the condensation r of a fixed right-hand side
//! b and the expansion of x_s = r, as `signorini::condensed` calls them (`SchurFactor`).
//! `one_process`: with the option of `solver.repeatable` (MUMPS on rank 0 alone).
//!
//! Rank 0 prints one line `SCHUR {json}` with FNV-1a hashes of the bits of S, r and the
//! expanded solution u. With `one_process` they must be those of a run on one rank: rank 0
//! factorises the same triplets in the same order with the same order as one rank does.

use std::process::ExitCode;

use mpi::traits::*;
use serde_json::json;
use signorini_mpi::petsc::mumps::{
    nested_dissection, NodeBases, SchurFactor, SchurRequest, Settings,
};
use signorini_mpi::petsc::{Matrix, PInt, Petsc};

/// FNV-1a over the bits of `v`, as hex.
fn hash(v: &[f64]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for x in v {
        for b in x.to_bits().to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    format!("{h:016x}")
}

/// The grid neighbours of unknown `v` (row-major, N × N).
fn neighbours(v: usize, n: usize) -> Vec<usize> {
    let (i, j) = (v / n, v % n);
    let mut out = Vec::with_capacity(4);
    if i > 0 {
        out.push(v - n);
    }
    if j > 0 {
        out.push(v - 1);
    }
    if j + 1 < n {
        out.push(v + 1);
    }
    if i + 1 < n {
        out.push(v + n);
    }
    out
}

fn run(
    world: &mpi::topology::SimpleCommunicator,
    petsc: &Petsc,
    args: &[String],
) -> Result<(), String> {
    let n: usize = args
        .first()
        .and_then(|a| a.parse().ok())
        .ok_or("usage: schur_repeat N [one_process]")?;
    let one_process = args.get(1).is_some_and(|a| a == "one_process");
    let total = n * n;
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    let (lo, hi) = (total * rank / size, total * (rank + 1) / size);
    // owned rows, complete, columns sorted
    let mut rowptr: Vec<PInt> = vec![0];
    let mut cols: Vec<PInt> = Vec::new();
    let mut vals: Vec<f64> = Vec::new();
    for v in lo..hi {
        let mut row: Vec<(usize, f64)> = neighbours(v, n).into_iter().map(|w| (w, -1.0)).collect();
        row.push((v, 4.01));
        row.sort_by_key(|e| e.0);
        for (c, x) in row {
            cols.push(c as PInt);
            vals.push(x);
        }
        rowptr.push(cols.len() as PInt);
    }
    let comm = petsc.comm();
    let mat = Matrix::from_csr(comm, 1, &rowptr, &cols, &vals).map_err(|e| e.to_string())?;
    let schur: Vec<usize> = ((n / 2) * n..(n / 2 + 1) * n).collect();
    let order = if rank == 0 {
        let mut xadj = vec![0usize];
        let mut adj = Vec::new();
        for v in 0..total {
            adj.extend(neighbours(v, n));
            xadj.push(adj.len());
        }
        let perm = nested_dissection(&xadj, &adj).map_err(|e| e.to_string())?;
        // the Schur variables last, the others in the dissection's order
        let mut by_pos: Vec<usize> = (0..total).collect();
        by_pos.sort_by_key(|&v| perm[v]);
        let mut order = vec![0usize; total];
        let rest = by_pos
            .iter()
            .filter(|&&v| !(schur[0]..=schur[n - 1]).contains(&v));
        for (p, &v) in rest.chain(schur.iter()).enumerate() {
            order[v] = p;
        }
        Some(order)
    } else {
        None
    };
    let bases = NodeBases {
        dim: 1,
        ..Default::default()
    };
    let request = SchurRequest {
        n: total,
        schur_rows: &schur,
        order: order.as_deref(),
        bases: &bases,
    };
    let mut f = SchurFactor::analyse(
        comm,
        &mat,
        &request,
        rank == 0,
        &Settings {
            one_process,
            controls: Default::default(),
        },
    )
    .map_err(|e| e.to_string())?;
    f.factorise().map_err(|e| e.to_string())?;
    let s = f.take_schur();
    let b: Vec<f64> = if rank == 0 {
        (0..total)
            .map(|i| ((i % 97) as f64 * 0.37).sin() + 0.1)
            .collect()
    } else {
        Vec::new()
    };
    let r = f.condense(&b).map_err(|e| e.to_string())?;
    let u = f.expand(&b, &r).map_err(|e| e.to_string())?;
    if rank == 0 {
        println!(
            "SCHUR {}",
            json!({"ranks": size, "n": total, "schur": n, "s": hash(&s), "r": hash(&r), "u": hash(&u)})
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(universe) = mpi::initialize() else {
        eprintln!("schur_repeat: MPI could not be initialised");
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    let petsc = match Petsc::init(&[]) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("schur_repeat: PETSc: {e}");
            world.abort(1);
        }
    };
    if let Err(e) = run(&world, &petsc, &args) {
        eprintln!("schur_repeat (rank {}): {e}", world.rank());
        world.abort(1);
    }
    drop(petsc);
    ExitCode::SUCCESS
}
