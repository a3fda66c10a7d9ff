//! Writes a structured test mesh, split between the MPI ranks, with fields that are known
//! functions of the coordinates, through `signorini_mpi::output::write_xdmf_hdf5`.
//!
//! ```text
//! mpirun -n 2 target/debug/examples/output_demo OUT_DIR DIM N [--contact] [--empty-last] [--time]
//! ```
//!
//! DIM 2: unit square, (N+1)² nodes, 2N² triangles. DIM 3: unit cube, (N+1)³ nodes, 6N³
//! tetrahedra. Node g (lexicographic, x fastest) has tag 5 + 3g, cell c has tag 100 + 2c.
//! Fields (x, y, z the node or cell-centroid coordinates):
//!   nodal  displacement = (x + 2y, xy − z, z/2 + x²), temperature = 3x − y + z
//!   cell   stress[k] = x + 10k + k·y (k = 0..9), von_mises = x² + y, pair = (x, y), rank
//!   contact surface: the nodes with y = 0 (2D) or z = 0 (3D), in node order, b their index
//!          on that side (x fastest); facets the segments (b, b + 1) (2D) or the triangles
//!          (b, b + 1, b + m + 1), (b, b + m, b + m + 1) of each square (3D, m = N + 1),
//!          square by square, facet f with tag 1000 + f;
//!          gap = x + 0.1, traction = (x, −x, 2x + y), code = b mod 3 − 1 (an integer field)
//! --empty-last: the last rank owns nothing (exercises zero-row ranks).
//! --time: rank 0 prints `write_seconds=…`.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use mpi::collective::CommunicatorCollectives;
use mpi::topology::Communicator;
use signorini_mpi::output::{write_xdmf_hdf5, ContactPiece, Field, Piece};

/// Rows `off .. off + cnt` of `total` owned by `rank` among `parts` (rank ≥ parts owns none).
fn block(total: usize, parts: usize, rank: usize) -> (usize, usize) {
    if rank >= parts {
        return (total, 0);
    }
    let lo = total * rank / parts;
    let hi = total * (rank + 1) / parts;
    (lo, hi - lo)
}

struct Args {
    dir: PathBuf,
    dim: usize,
    n: usize,
    contact: bool,
    empty_last: bool,
    time: bool,
}

fn parse() -> Result<Args, String> {
    let usage = "usage: output_demo OUT_DIR DIM N [--contact] [--empty-last] [--time]";
    let mut pos = Vec::new();
    let (mut contact, mut empty_last, mut time) = (false, false, false);
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "--contact" => contact = true,
            "--empty-last" => empty_last = true,
            "--time" => time = true,
            _ if a.starts_with("--") => return Err(format!("unknown option {a}; {usage}")),
            _ => pos.push(a),
        }
    }
    if pos.len() != 3 {
        return Err(usage.to_string());
    }
    let dim: usize = pos[1].parse().map_err(|_| usage.to_string())?;
    let n: usize = pos[2].parse().map_err(|_| usage.to_string())?;
    if !(dim == 2 || dim == 3) || n == 0 {
        return Err(format!("DIM must be 2 or 3 and N ≥ 1; {usage}"));
    }
    Ok(Args {
        dir: PathBuf::from(&pos[0]),
        dim,
        n,
        contact,
        empty_last,
        time,
    })
}

fn coords_of(g: usize, dim: usize, n: usize) -> [f64; 3] {
    let m = n + 1;
    let h = 1.0 / n as f64;
    let i = g % m;
    let j = (g / m) % m;
    let k = if dim == 3 { g / (m * m) } else { 0 };
    [i as f64 * h, j as f64 * h, k as f64 * h]
}

/// Global node numbers of global cell `c`.
fn cell_nodes(c: usize, dim: usize, n: usize, out: &mut Vec<usize>) {
    let m = n + 1;
    if dim == 2 {
        let (sq, t) = (c / 2, c % 2);
        let (i, j) = (sq % n, sq / n);
        let a = j * m + i;
        let (b, cc, d) = (a + 1, a + m, a + m + 1);
        if t == 0 {
            out.extend_from_slice(&[a, b, d]);
        } else {
            out.extend_from_slice(&[a, d, cc]);
        }
    } else {
        // Kuhn split of a cube into 6 tetrahedra along the diagonal 0 → 7
        let (cube, t) = (c / 6, c % 6);
        let (i, j, k) = (cube % n, (cube / n) % n, cube / (n * n));
        let v = |di: usize, dj: usize, dk: usize| (k + dk) * m * m + (j + dj) * m + (i + di);
        let v0 = v(0, 0, 0);
        let v7 = v(1, 1, 1);
        // paths 0 → 7 through the cube edges: each permutation of the axes
        let perms = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        let p = perms[t];
        let mut d = [0usize; 3];
        d[p[0]] = 1;
        let v1 = v(d[0], d[1], d[2]);
        d[p[1]] = 1;
        let v2 = v(d[0], d[1], d[2]);
        out.extend_from_slice(&[v0, v1, v2, v7]);
    }
}

fn main() -> ExitCode {
    let Some(universe) = mpi::initialize() else {
        eprintln!("output_demo: MPI initialisation failed");
        return ExitCode::from(3);
    };
    let world = universe.world();
    let rank = world.rank() as usize;
    let size = world.size() as usize;
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("output_demo: {e}");
            return ExitCode::from(2);
        }
    };
    let (dim, n) = (args.dim, args.n);
    let parts = if args.empty_last && size > 1 {
        size - 1
    } else {
        size
    };

    let n_nodes = (n + 1).pow(dim as u32);
    let n_cells = if dim == 2 { 2 * n * n } else { 6 * n * n * n };
    let (node_off, node_cnt) = block(n_nodes, parts, rank);
    let (cell_off, cell_cnt) = block(n_cells, parts, rank);

    let coords: Vec<[f64; 3]> = (node_off..node_off + node_cnt)
        .map(|g| coords_of(g, dim, n))
        .collect();
    let node_ids: Vec<u64> = (node_off..node_off + node_cnt)
        .map(|g| 5 + 3 * g as u64)
        .collect();
    let mut conn = Vec::with_capacity(cell_cnt * (dim + 1));
    for c in cell_off..cell_off + cell_cnt {
        cell_nodes(c, dim, n, &mut conn);
    }
    let cell_ids: Vec<u64> = (cell_off..cell_off + cell_cnt)
        .map(|c| 100 + 2 * c as u64)
        .collect();

    let displacement: Vec<f64> = coords
        .iter()
        .flat_map(|&[x, y, z]| [x + 2.0 * y, x * y - z, 0.5 * z + x * x])
        .collect();
    let temperature: Vec<f64> = coords.iter().map(|&[x, y, z]| 3.0 * x - y + z).collect();

    let centroids: Vec<[f64; 3]> = conn
        .chunks_exact(dim + 1)
        .map(|cell| {
            let mut s = [0.0; 3];
            for &g in cell {
                let p = coords_of(g, dim, n);
                for d in 0..3 {
                    s[d] += p[d];
                }
            }
            s.map(|v| v / (dim + 1) as f64)
        })
        .collect();
    let stress: Vec<f64> = centroids
        .iter()
        .flat_map(|&[x, y, _]| (0..9).map(move |k| x + 10.0 * k as f64 + k as f64 * y))
        .collect();
    let von_mises: Vec<f64> = centroids.iter().map(|&[x, y, _]| x * x + y).collect();
    let pair: Vec<f64> = centroids.iter().flat_map(|&[x, y, _]| [x, y]).collect();
    let rank_field = vec![rank as f64; cell_cnt];

    // contact nodes: bottom side, in global node order
    let bottom: Vec<usize> = if dim == 2 {
        (0..=n).collect()
    } else {
        (0..(n + 1) * (n + 1)).collect()
    };
    let (c_off, c_cnt) = block(bottom.len(), parts, rank);
    let c_coords: Vec<[f64; 3]> = bottom[c_off..c_off + c_cnt]
        .iter()
        .map(|&g| coords_of(g, dim, n))
        .collect();
    let c_ids: Vec<u64> = bottom[c_off..c_off + c_cnt]
        .iter()
        .map(|&g| 5 + 3 * g as u64)
        .collect();
    let gap: Vec<f64> = c_coords.iter().map(|&[x, _, _]| x + 0.1).collect();
    let traction: Vec<f64> = c_coords
        .iter()
        .flat_map(|&[x, y, _]| [x, -x, 2.0 * x + y])
        .collect();
    let code: Vec<f64> = (c_off..c_off + c_cnt)
        .map(|b| (b % 3) as f64 - 1.0)
        .collect();
    // facets of the bottom side (surface node numbers = bottom indices)
    let m = n + 1;
    let all_facets: Vec<[usize; 3]> = if dim == 2 {
        (0..n).map(|i| [i, i + 1, 0]).collect()
    } else {
        (0..n * n)
            .flat_map(|q| {
                let b = (q / n) * m + q % n;
                [[b, b + 1, b + m + 1], [b, b + m, b + m + 1]]
            })
            .collect()
    };
    let (f_off, f_cnt) = block(all_facets.len(), parts, rank);
    let facets: Vec<usize> = all_facets[f_off..f_off + f_cnt]
        .iter()
        .flat_map(|f| f[..dim].to_vec())
        .collect();
    let facet_ids: Vec<u64> = (f_off..f_off + f_cnt).map(|f| 1000 + f as u64).collect();

    let piece = Piece {
        dim,
        n_nodes_global: n_nodes,
        node_offset: node_off,
        coords: &coords,
        node_ids: &node_ids,
        n_cells_global: n_cells,
        cell_offset: cell_off,
        connectivity: &conn,
        cell_ids: &cell_ids,
        nodal: vec![
            Field {
                name: "displacement",
                ncomp: 3,
                data: &displacement,
                codes: None,
            },
            Field {
                name: "temperature",
                ncomp: 1,
                data: &temperature,
                codes: None,
            },
        ],
        cellwise: vec![
            Field {
                name: "stress",
                ncomp: 9,
                data: &stress,
                codes: None,
            },
            Field {
                name: "von_mises",
                ncomp: 1,
                data: &von_mises,
                codes: None,
            },
            Field {
                name: "pair",
                ncomp: 2,
                data: &pair,
                codes: None,
            },
            Field {
                name: "rank",
                ncomp: 1,
                data: &rank_field,
                codes: None,
            },
        ],
        contact: args.contact.then(|| ContactPiece {
            n_global: bottom.len(),
            offset: c_off,
            coords: &c_coords,
            node_ids: &c_ids,
            n_facets_global: all_facets.len(),
            facet_offset: f_off,
            facets: &facets,
            facet_ids: &facet_ids,
            fields: vec![
                Field {
                    name: "gap",
                    ncomp: 1,
                    data: &gap,
                    codes: None,
                },
                Field {
                    name: "traction",
                    ncomp: 3,
                    data: &traction,
                    codes: None,
                },
                Field {
                    name: "code",
                    ncomp: 1,
                    data: &code,
                    codes: Some("the bottom index mod 3, minus 1"),
                },
            ],
        }),
    };

    world.barrier();
    let t0 = Instant::now();
    let res = write_xdmf_hdf5(&world, &args.dir, &piece);
    world.barrier();
    let secs = t0.elapsed().as_secs_f64();
    match res {
        Ok(()) => {
            if args.time && rank == 0 {
                println!("write_seconds={secs:.3} nodes={n_nodes} cells={n_cells} ranks={size}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            // one write per line, so the lines of the ranks do not interleave
            let line = format!("output_demo rank {rank}: {e}\n");
            let _ = std::io::stderr().write_all(line.as_bytes());
            // let every rank report before mpirun reacts to the first non-zero exit
            world.barrier();
            ExitCode::from(1)
        }
    }
}
