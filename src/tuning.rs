//! Every constant that chooses an algorithm or a path, in one place.
//!
//! What is here: the limits, ratios, counts and fractions by which the solver picks a linear
//! solver, a path (condensed or plain), a candidate set, a model size, a number of passes or
//! factorisations, a partition granularity or a thread count. What is not: the tolerances of
//! a convergence or acceptance test (they say when an answer is right, next to the test that
//! reads them), file-format constants and the limits of the case file.
//!
//! Each constant's doc says what it chooses, the measurement that justifies its value (with
//! the document that holds it), the machine it was measured on and whether it is
//! machine-specific: a ratio of two speeds (dense against sparse flops, one thread against
//! two) changes with the CPU and the BLAS, a count of nodes or a fraction of a zone does not.
//! "Not measured" says that nothing beyond the stated reasoning backs the value. For a
//! machine-specific constant the doc names how to measure it again on another machine.
//!
//! Machines named below. "The 2-core AMD EPYC": the shared machine of every measurement of
//! docs/numbers.md that names no other (family 25, model 17, AVX-512, 2 cores shared with
//! other jobs, so wall times are noisy). "The Intel Emerald Rapids": the 2-core Xeon of
//! docs/numbers.md, "OpenBLAS' kernels on an Intel Emerald Rapids machine" (AVX-512,
//! OpenBLAS' SkylakeX kernels by the solver's restart).

// ---------------------------------------------------------------------------------------------
// Linear solver choice
// ---------------------------------------------------------------------------------------------

/// `solver.preset = "auto"`: 3D meshes from this many unknowns take the iterative preset.
/// Measured: bench/results/ordering.md, 2 ranks, the floating ball: 12 063 unknowns 0.34 s
/// direct, 0.29 s iterative; 17 856: 0.79 / 0.50 s; 126 801: 31.5 / 6.0 s. 2D stays direct
/// (561 112 unknowns: contact 4.0 s direct, 4.6 s iterative). The 2-core AMD EPYC.
/// Machine-specific (a ratio of sparse-direct to Krylov speed, mild: the crossover lies
/// where both take a fraction of a second); on another machine: `scripts/bench-ordering
/// --ball ...` and the dofs where the two columns cross.
pub const AUTO_ITERATIVE_3D_DOFS: usize = 10_000;

/// The auto preset solves a 3D body pair whose slave side is this many times as stiff as its
/// master (contact moduli E / (1 − ν²)) directly: the iterative preset's preconditioner
/// corrects the held slave nodes on the slave side. Measured on the quarter ball on a block of
/// cases/bodies/hertz_bodies3d.toml at 16 647 unknowns, 2 ranks, the block (ν 0.2) as slave,
/// its E varied against the ball's 1 (ν 0.3): GMRES iterations in the exact steps 88 / 188 /
/// 275 / 499 at E = 3 / 30 / 300 / 3 000, and a breakdown at 3e6; the ball as slave 36–41 at
/// every E. By those counts the iterative run costs about what the direct preset's does from a
/// ratio of a few hundred (at 85 374 unknowns and E = 3: 2.3–2.9 × T_linear iterative against
/// 6.7–9.2 × direct, ~90 iterations; an estimate, not a measured crossover). Not
/// machine-specific (iteration counts).
pub const STIFF_SLAVE_RATIO: f64 = 100.0;

/// Per cent of workspace over MUMPS' estimate (ICNTL(14)): the direct preset's option string
/// (linsolve.rs writes the same 40) and petsc/mumps.rs's own MUMPS instances. Measured: one 2-rank
/// 3D Cholesky of 396 k unknowns failed with DIVERGED_PC_FAILED at the default and passed
/// when rerun: the estimate depends on the partition (docs/numbers.md, "Linear solves and
/// assembly"). The 2-core AMD EPYC. Not machine-specific.
pub const WORKSPACE_PERCENT: i32 = 40;

// ---------------------------------------------------------------------------------------------
// The iterative preset
// ---------------------------------------------------------------------------------------------

/// GMRES restart of the iterative preset (`-ksp_gmres_restart`): larger than the longest
/// solve measured (185 iterations, the 3D block at 112 890 unknowns, linsolve.rs), so GMRES
/// does not restart. Not measured as a choice; not machine-specific (memory: one vector per
/// iteration).
pub const ITERATIVE_RESTART: usize = 200;

/// Iteration cap of the iterative preset (`-ksp_max_it`): a solve that needs more has
/// failed. Not measured; not machine-specific.
pub const ITERATIVE_MAX_IT: usize = 2000;

/// From this many ranks GAMG's Galerkin products use the all-at-once algorithm
/// (`-matptap_via allatonce`): repeatable sums and less memory (L7 on 4 ranks: 256 vs 326 MB
/// peak per rank), but about 30 % slower on 2 ranks, where the default is repeatable too
/// (linsolve.rs). The 2-core AMD EPYC. The rule is one of repeatability, not machine-specific.
pub const ALLATONCE_MIN_RANKS: usize = 3;

/// An inexact step reduces its warm start's residual by this factor. Measured on 3D Hertz,
/// 2 ranks: a fixed 1e-4 ‖b‖ made the set chatter (79 k unknowns: no convergence in 100
/// steps); a fixed 1e-6 ‖b‖ followed the plain path's sets at 79 k but not at 526 k (11 steps
/// instead of 7) (step_system/reuse.rs). The 2-core AMD EPYC. Not machine-specific (step counts).
pub const INEXACT_REDUCTION: f64 = 1e-6;

/// The half-space predictor's first solve reduces its residual by this factor. Measured at
/// 527 k unknowns (3D Hertz, 2 ranks): 1e-3, 1e-2, 1e-1 took 7, 5, 4 iterations and gave
/// predicted sets of 1 579, 1 578, 1 578 nodes (final set 1 576) (step_system/reuse.rs). The 2-core
/// AMD EPYC. Not machine-specific (iteration counts).
pub const PREDICTOR_REDUCTION: f64 = 1e-2;

/// "auto": the preconditioner is set up anew when a step needed more than this multiple of
/// the iterations per decade that the solve after the last setup needed ("the hierarchy set
/// up anew when the Krylov rate grows by 30 %", docs/numbers.md). Not measured as a value;
/// not machine-specific (iteration counts). A ratio of setup to iteration time would make
/// it machine-specific; it is deliberately counts only.
pub const REBUILD_GROWTH: f64 = 1.3;

/// A solve on a reused preconditioner may make this multiple of the iterations its rate
/// predicts before it stops and the preconditioner is set up anew. Not measured; not
/// machine-specific (iteration counts).
pub const REUSE_BUDGET: f64 = 4.0;

/// A solve's rate (iterations per decade) is compared only after it reduced its residual by
/// this many decades ...
pub const RATE_MIN_DECADES: f64 = 1.5;

/// ... and made this many iterations: a nearly converged warm start says nothing about the
/// preconditioner. Not measured; not machine-specific.
pub const RATE_MIN_ITERATIONS: usize = 4;

// ---------------------------------------------------------------------------------------------
// The complementarity parameter
// ---------------------------------------------------------------------------------------------

/// The default c = DEFAULT_C_FACTOR · E h_c^(d−2) (plain_path::default_c): c only chooses the
/// path of the iteration (which set a step tries), not its solution. Measured on 19 cases with
/// the former default E / h_c and with c = κ E h_c^(d−2), κ = 1, 10, 100, 1000 (2 ranks,
/// friction and frictionless, 2D and 3D, direct and iterative presets): every run converged with
/// the same factorisations; Newton steps summed over the friction cases (Coulomb: the Cattaneo
/// load history, the floating and the held Hertz disk, the hemisphere's load history; Tresca:
/// the floating disk, the held 3D block) 99 with E / h_c, 91 / 89 / 103 / 106 with κ = 1 / 10 /
/// 100 / 1000, frictionless cases the same with every κ. κ = 100 takes the former default's
/// steps on the finely meshed cases most tests run (the Cattaneo disk of h_c = 0.0061: 21 steps
/// in both, the hemisphere's: 41 in both) and at most 2 more elsewhere (the floating Tresca disk:
/// 23 against 21). The 2-core AMD EPYC. Not machine-specific (step counts).
pub const DEFAULT_C_FACTOR: f64 = 100.0;

// ---------------------------------------------------------------------------------------------
// Reuse of a factorisation (direct preset, `solver.reuse`)
// ---------------------------------------------------------------------------------------------

/// "always": Krylov iterations a reuse may make before the step refactorises; fixed, so runs
/// and tests are reproducible. Not measured as a value ("up to the budget of 30",
/// docs/numbers.md); not machine-specific.
pub const ALWAYS_BUDGET: usize = 30;

/// "auto" reuses only if the expected Krylov solve costs at most this fraction of a
/// factorisation step: room for the estimate of one iteration. Not measured; not
/// machine-specific.
pub const AUTO_MARGIN: f64 = 0.75;

/// One Krylov iteration on the factorisation costs this many triangular solve pairs
/// (MatSolve, plus MatMult and orthogonalisation). An estimate, not measured; nearly
/// machine-independent (all three are memory-bound).
pub const ITERATION_PER_SOLVE: f64 = 1.25;

/// One flop of a triangular solve pair costs this many flops of the numeric factorisation.
/// Measured (docs/numbers.md, "solver.reuse = "auto" from counts, not timings"): Hertz L4,
/// 12 618 dofs, 1 rank, 3 runs: factorisation 8.9e7 flops in 0.030 s (median), one reuse
/// iteration 5.9 ms: 4.4; 4 taken. The 2-core AMD EPYC. Machine-specific (memory bandwidth
/// against BLAS-3 rate), fixed on purpose so that the path never depends on timings; on
/// another machine repeat that calibration (`reuse = "always"`, summary.json's timings).
pub const SOLVE_FLOP_COST: f64 = 4.0;

/// GMRES restart of the reuse solver: no "auto" budget exceeds it, so GMRES never restarts.
/// Not measured; not machine-specific.
pub const REUSE_RESTART: usize = 200;

// ---------------------------------------------------------------------------------------------
// The condensed (Schur) path: candidates and dense limits
// ---------------------------------------------------------------------------------------------

/// More contact nodes than this and the condensed path is not tried: every rank holds a
/// record of 15 values per contact node (12 MB at the limit). Not measured as a speed;
/// a memory bound, not machine-specific.
pub const MAX_CONTACT_NODES: usize = 100_000;

/// More Schur variables than this and the plain path takes over before anything is
/// factorised: rank 0 holds S as one dense matrix of their square (8 000: 512 MB) and the
/// dense work grows as their cube. A memory bound of rank 0, not a measured speed;
/// machine-specific only through rank 0's memory.
pub const MAX_SCHUR_DOFS: usize = 8000;

/// Dense work (n³ flops) always allowed; beyond it the dense work must pay against K_p's
/// factorisation. Not measured as a value: "about 0.1 s of LAPACK on one core" (schur/frictionless.rs;
/// LAPACK ran at 13.6 GFlop/s on one core there, at 40 GFlop/s with AVX-512 kernels,
/// docs/friction.md); machine not named. Machine-specific (a dense flop rate); on another
/// machine: `scripts/bench-dense-threads`, the 1-thread LU time at n = 1 000.
pub const DENSE_FLOOR_FLOPS: f64 = 1e9;

/// In 2D the dense work may be this many times K_p's factorisation flops. Measured: held
/// Hertz disk, 698 352 unknowns, Coulomb, 2 ranks: factorisation 1.1e10 flops (1.4 s); dense
/// work on 2 000 candidates (6.4e10 flops) 1.6 s: a ratio of about 6; 8 taken (the plain path
/// took 34.0 s, the condensed 9.7 s). OpenBLAS' AVX-512 kernels: the Intel Emerald Rapids
/// (earlier, LAPACK 13.6 against MUMPS' 0.8 GFlop/s, it was 4). Machine-specific: on another
/// machine `scripts/bench-friction --levels 12 --held`, the log's factorisation and dense
/// seconds and flops. In 3D the ratio is 1 (not measured beyond).
pub const DENSE_SPEEDUP_2D: f64 = 8.0;

/// The first candidates: the 1/FIRST_FRACTION of a pair's contact nodes with the smallest
/// gaps. Not measured as a value; not machine-specific.
pub const FIRST_FRACTION: usize = 8;

/// The first candidate set holds at least this many contact nodes (all if fewer). Not
/// measured; not machine-specific.
pub const MIN_CANDIDATES: usize = 64;

/// All pairs' first candidates together hold at most 1/FIRST_SCHUR_SHARE of the Schur limit,
/// leaving room for growth (schur/frictionless.rs `Growth::new`). Measured effect: the floating disk at 698 352 unknowns capped at 2 000 nodes
/// where its zone asked for 2 232, then a second pass (docs/numbers.md). Not machine-specific.
pub const FIRST_SCHUR_SHARE: usize = 2;

/// A growth round multiplies every pair's number of candidates by this (schur/frictionless.rs). Not measured; not machine-specific.
pub const CANDIDATE_GROWTH: usize = 2;

/// Where the half-space model located the zone, the first candidates hold (1 +
/// 1/LOCATED_MARGIN) × its nodes in contact. Measured: rolling Hertz disk, 42 k–345 k
/// unknowns, 124 / 496 / 992 located, 124 / 495 / 991 in the final Coulomb set; the floating
/// disk at 345 k, 993 located, 969 frictionless, 947 Coulomb (a fourth more exceeds what
/// pays). The 2-core AMD EPYC. Not machine-specific (counts).
pub const LOCATED_MARGIN: usize = 8;

/// Rounds of candidate growth before the plain path takes over. Not measured; not
/// machine-specific.
pub const MAX_ROUNDS: usize = 8;

/// A wide zone's Schur variables: the 1/BAND_FRACTION of its nodes nearest its edge (the band
/// doubles each pass). Justified by the model's zone edge: 2.3 % and 0.5 % of the zone's width from
/// the final one on the 2D Hertz disk at 10–50 × its load, 1.5 % of the radius on the 3D
/// ball (schur/frictionless.rs). Not machine-specific (geometry).
pub const BAND_FRACTION: usize = 8;

/// The nested iteration's coarsest level has at least this many points. Not measured; not
/// machine-specific.
pub const COARSEST: usize = 8;

/// The coarsening samples the nearest-neighbour distance at about this many points (dense.rs
/// `coarsen`, `step = (n / 256).max(1)`): O(256 n) work for a median. Not measured; not
/// machine-specific.
pub const SPACING_SAMPLES: usize = 256;

/// The coarsening's first radius in units of the median spacing h (`0.99 * h`, doubled
/// before each level): just under 2 h, so that every second point of a uniform line stays.
/// Not measured; not machine-specific (geometry).
pub const COARSEN_RADIUS: f64 = 0.99;

/// A coarse level is kept only where it holds at most COARSEN_KEEP[0] / COARSEN_KEEP[1] of
/// the level before (dense.rs `4 * kept.len() <= 3 * prev.len()`): graded meshes try the next
/// radius. Not measured; not machine-specific.
pub const COARSEN_KEEP: [usize; 2] = [3, 4];

// ---------------------------------------------------------------------------------------------
// The half-space model (predictor)
// ---------------------------------------------------------------------------------------------

/// The model holds at most this many contact nodes: its dense compliance has this squared
/// entries on rank 0 (72 MB). Not measured as a limit; its cost there: 0.8 s of LAPACK
/// Cholesky at 3 000 nodes and 1 578 active, 3D Hertz at 527 k unknowns (docs/numbers.md).
/// The 2-core AMD EPYC. A memory bound first; the time makes it mildly machine-specific.
pub const MAX_MODEL_NODES: usize = 3000;

/// The model represents MODEL_MARGIN × the nodes that penetrate after the first solve (the
/// final set of 3D Hertz is 1.2 × it), at least MIN_MODEL_NODES, at most MAX_MODEL_NODES
/// while these cover FINE_MODEL_COVER of them, else at most MAX_REPRESENTED by a coarser
/// subset. Measured: 3D Hertz, 527 k unknowns: 4 steps from a coarse model of 3 840 nodes,
/// 3 from the fine one of 3 000 (halfspace/). The 2-core AMD EPYC. Not machine-specific.
pub const MODEL_MARGIN: usize = 3;
/// See [`MODEL_MARGIN`]. Not measured.
pub const MIN_MODEL_NODES: usize = 256;
/// See [`MODEL_MARGIN`]. Not measured.
pub const MAX_REPRESENTED: usize = 24_000;

/// The fine model is used while FINE_MODEL_COVER[0] / FINE_MODEL_COVER[1] × the penetrating
/// nodes fit in MAX_MODEL_NODES (halfspace/). Not
/// measured; not machine-specific.
pub const FINE_MODEL_COVER: [usize; 2] = [3, 2];

/// The model's solution counts as truncated where a node of the last 1/MODEL_BORDER_PART
/// of its nodes (by clearance) comes into contact (halfspace/).
/// Not measured; not machine-specific.
pub const MODEL_BORDER_PART: usize = 10;

/// The model's nodes where it locates a zone: a coarse subset of at most 512 first (a
/// contact line of 8 193 nodes: 257 model nodes, 0.04 s on 2 ranks), then up to
/// MAX_MODEL_NODES where that does not converge (a floating ball's zone four model nodes
/// wide). The 2-core AMD EPYC. Not machine-specific (counts).
pub const LOCATE_MODEL_NODES: [usize; 2] = [512, MAX_MODEL_NODES];

// ---------------------------------------------------------------------------------------------
// Coulomb's passes with a held sticking zone
// ---------------------------------------------------------------------------------------------

/// Factorisations of K_p at most in a Coulomb start whose zone's interior is held sticking;
/// then the plain path. Below what the plain path costs: 9–19 LU steps on the wide zones of
/// docs/numbers.md ("Wide zones with friction"). The 2-core AMD EPYC. Not machine-specific
/// (factorisation counts).
pub const MAX_STICK_FACTORISATIONS: usize = 8;

/// Factorisations at most in a held zone's first pass (every candidate condensed, then the
/// held zone and one pass where its frictionless set moves). Not measured as a value; not
/// machine-specific.
pub const FIRST_STICK_FACTORISATIONS: usize = 3;

/// Factorisations at most in a Coulomb load step whose warm set's interior is held sticking.
/// Measured (docs/numbers.md, "Load steps on wide zones"): where the warm set predicts the
/// step one pass solves it; a floating disk rolling under a large traction took 5 passes
/// (changes 304, 86, 21, 1, 3), about what its 12 plain steps cost. The 2-core AMD EPYC.
/// Not machine-specific.
pub const WARM_STICK_FACTORISATIONS: usize = 2;

// ---------------------------------------------------------------------------------------------
// Partitioning
// ---------------------------------------------------------------------------------------------

/// Load imbalance PT-Scotch may leave between the parts: PETSc's default, 1 % (measured
/// balance max/mean ≤ 1.0097, bench/results/dist-partition.md). Not measured as a choice;
/// not machine-specific. Used by the mesh reader's partition and by `partition`.
pub const SCOTCH_IMBALANCE: f64 = 0.01;

/// Most cells in one aggregate of the coarse graph PT-Scotch partitions. Measured
/// (bench/results/dist-partition.md, Hertz L7, 557 526 triangles): PT-Scotch 0.537 → 0.161 s
/// on 4 ranks, edge cut +25 % (2 ranks) and +32 % (4 ranks) against 1-cell aggregates. The
/// 2-core AMD EPYC, loaded. Not machine-specific (graph size against cut).
pub const AGGREGATE_CELLS: usize = 16;

/// Fewest coarse vertices per part: smaller meshes get smaller aggregates. Not measured;
/// not machine-specific.
pub const COARSE_PER_PART: usize = 256;

// ---------------------------------------------------------------------------------------------
// BLAS threads and memory
// ---------------------------------------------------------------------------------------------

/// The smallest dense dimension whose phase runs on every core of rank 0's node. Measured
/// (`scripts/bench-dense-threads`, docs/numbers.md, "Rank 0's dense phases on the cores of
/// its node"): LU with 2 threads took 0.91–1.57 of one thread's time from 200 to 700 unknowns
/// and 0.59–0.84 from 1 000 on. The 2-core AMD EPYC. Machine-specific (core count, BLAS
/// kernels); on another machine `scripts/bench-dense-threads --dims ...`, the first n whose
/// ratio stays below 1.
pub const WIDE_MIN_DIM: usize = 1000;

/// Buffers at least this large (bytes) are memory maps advised for transparent huge pages
/// (bigbuf.rs): with 4 KiB pages 0.13 of 0.43 s of the 396 k-unknown box's assembly went to
/// page faults. The 2-core AMD EPYC. 2 MiB is x86-64's huge page: machine-specific (Linux
/// gives the size in /sys/kernel/mm/transparent_hugepage/hpage_pmd_size).
pub const MAP_FROM: usize = 2 << 20;

// ---------------------------------------------------------------------------------------------
// Krylov solves of the contact steps
// ---------------------------------------------------------------------------------------------

/// A set that recurs on Krylov solves first divides their relative tolerance by this
/// (plain_path/iteration.rs `tighten_solver`) before the recurrence counts as cycling. Measured:
/// the quarter ball of cases/hertz3d at 1 887 747 unknowns, 2 ranks, the iterative preset at
/// its rtol 1e-10: one edge node flipped between two sets (|C_n| 6.7e-10 and 3.3e-6) and the
/// run ended as cycling; at 1e-13 the same start stopped after 2 exact steps on 3 808 nodes.
/// Not machine-specific (a solver tolerance).
pub const TIGHTEN_ON_RECURRENCE: f64 = 1e3;

/// The tightest relative tolerance [`TIGHTEN_ON_RECURRENCE`] goes to: about what GMRES reaches
/// in double precision on these systems (1e-13 reached in 23–29 iterations in the run above).
/// Not measured as a limit; not machine-specific.
pub const TIGHTEST_RTOL: f64 = 1e-14;
