//! Tests of the dense Coulomb iteration on small synthetic compliances.

use super::*;
use crate::contact::Frame;
use crate::signorini::boundary::ContactNode;
use crate::signorini::dense::pack_upper;

/// A coupled line of `n` candidates (2D) pressed onto a flat obstacle and pushed sideways:
/// normal and tangential compliances C_ij = exp(−|i−j| / 8) (positive definite, uncoupled
/// between the directions), d₀ a parabola deepest at the middle along the normal and a
/// uniform sideways push `push`; μ = 0.3. The middle sticks, the edges slip (Cattaneo).
fn pushed_line(n: usize, push: f64) -> (DMatrix<f64>, Vec<f64>, ContactBoundary) {
    let k = |i: usize, j: usize| (-(i as f64 - j as f64).abs() / 8.0).exp();
    let cmat = DMatrix::from_fn(2 * n, 2 * n, |r, q| {
        if r % 2 == q % 2 {
            k(r / 2, q / 2)
        } else {
            0.0
        }
    });
    let mid = (n / 2) as f64;
    let d0: Vec<f64> = (0..2 * n)
        .map(|r| {
            let t = ((r / 2) as f64 - mid) / mid;
            if r % 2 == 0 {
                -1.0 + 2.0 * t * t
            } else {
                push
            }
        })
        .collect();
    let nodes = (0..n)
        .map(|i| ContactNode {
            node: i,
            pair: 0,
            mu: 0.3,
            tag: i as u64,
            row: 0,
            local_row: 0,
            x: [i as f64, 0.0, 0.0],
            frame: Frame::new([0.0, 1.0, 0.0], 2).expect("unit normal"),
            gap: 0.0,
            weight: 0.0,
            bound: 0.0,
            u_t_ref: [0.0; 2],
        })
        .collect();
    let cb = ContactBoundary {
        nodes,
        n_global: n,
        offset: 0,
        on_contact_boundary: Vec::new(),
        excluded_dirichlet: 0,
        obstacles: Vec::new(),
        keys: Default::default(),
        modes: std::sync::Arc::new(crate::mesh::BodyModes::none(2)),
        stiffness: 0.0,
    };
    (cmat, d0, cb)
}

/// The pushed line ([`pushed_line`]) with no free modes.
struct Line {
    cmat: DMatrix<f64>,
    d0: Vec<f64>,
    g: DMatrix<f64>,
    cb: ContactBoundary,
}

impl Line {
    fn new(n: usize, push: f64) -> Line {
        let (cmat, d0, cb) = pushed_line(n, push);
        Line {
            cmat,
            d0,
            g: DMatrix::zeros(2 * n, 0),
            cb,
        }
    }

    /// Its dense Coulomb iteration (μ = 0.3) with c, the settled rows on.
    fn dense(&self, c: f64) -> DenseIteration<'_> {
        DenseIteration {
            dim: 2,
            cmat: CMatrix::Full(&self.cmat),
            d0: &self.d0,
            g: &self.g,
            phi: &[],
            cb: &self.cb,
            law: Law::Coulomb,
            c,
            max_steps: 100,
            tol_u: 1e-10,
            settle: true,
            stiff: None,
        }
    }
}

/// S = C⁻¹ of a [`Line`] as the condensed path keeps it (its upper triangle packed), r = S d₀,
/// S G and Gᵀ S G: what a [`Stiff`] borrows.
struct StiffParts {
    s_packed: Vec<f64>,
    r: Vec<f64>,
    sg: DMatrix<f64>,
    gsg: DMatrix<f64>,
}

impl StiffParts {
    fn of(line: &Line) -> StiffParts {
        let s = line.cmat.clone().try_inverse().expect("SPD");
        let r = (&s * DVector::from_column_slice(&line.d0))
            .as_slice()
            .to_vec();
        let sg = &s * &line.g;
        let gsg = line.g.transpose() * &sg;
        let s_packed = pack_upper(s.as_slice().to_vec(), line.cmat.nrows());
        StiffParts {
            s_packed,
            r,
            sg,
            gsg,
        }
    }

    fn stiff(&self) -> Stiff<'_> {
        Stiff {
            s: CMatrix::Upper {
                n: self.r.len(),
                packed: &self.s_packed,
            },
            r: &self.r,
            sg: self.sg.clone(),
            gsg: self.gsg.clone(),
        }
    }
}

/// Runs `f` on a thread with a stack of its own: a multithreaded BLAS may take more than a
/// test thread's 2 MB.
fn on_big_stack(f: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(f)
        .expect("thread")
        .join()
        .expect("the test");
}

#[test]
fn nested_coulomb_ends_in_the_plain_runs_solution_in_fewer_fine_steps() {
    on_big_stack(nested_against_plain);
}

/// A 2D slip row without spring and right-hand side ties λ_τ = −q λ_n: the node keeps one
/// unknown and one row, and the solution still satisfies every row of the set.
#[test]
fn a_settled_slip_nodes_tangential_force_is_tied_to_its_normal_force() {
    on_big_stack(|| {
        let n = 9;
        let line = Line::new(n, 0.1);
        let (dense, cb) = (line.dense(1.0), &line.cb);
        // the outer four nodes slip outwards (settled rows), the middle five stick
        let coef = |q: usize| if q < 2 { -0.3 } else { 0.3 };
        let row = |q: usize| {
            if q < 2 || q >= n - 2 {
                CoulombRow::Slip {
                    l: [[0.0; 2]; 2],
                    q: [coef(q), 0.0],
                    r: [0.0; 2],
                }
            } else {
                CoulombRow::Stick
            }
        };
        let set = ActiveSet {
            normal: vec![true; n],
            tangential: Some((0..n).map(row).collect()),
            spring_floor: 0.0,
            stick_active: false,
        };
        let sys = dense.system(&set).expect("rows");
        assert_eq!(sys.cols.len(), 4 + 2 * 5);
        let x = solve_system(&sys).expect("regular");
        let (lam, u, _) = dense.unknowns(&sys, &x);
        let (su, sl) = (
            u.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
            lam.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
        );
        for q in 0..n {
            assert!(
                (u[2 * q] + cb.nodes[q].gap).abs() <= 1e-12 * su,
                "u_n of {q}"
            );
            if set.slip(q) {
                let tied = lam[2 * q + 1] + coef(q) * lam[2 * q];
                assert!(tied.abs() <= 1e-12 * sl, "λ_τ of {q}: {tied}");
                assert!(lam[2 * q + 1] != 0.0);
            } else {
                assert!(u[2 * q + 1].abs() <= 1e-12 * su, "u_τ of {q}");
            }
        }
    });
}

/// The primal form (on S = C⁻¹ itself) against the dual form on C, on the pushed line
/// pressed in everywhere (every node active: the primal form has the slipping nodes'
/// tangential displacements alone as unknowns): the same final states and λ; S and C packed
/// as the condensed path keeps them, and the dual form on the packed C as on the full one.
#[test]
fn the_primal_form_ends_where_the_dual_form_ends() {
    on_big_stack(|| {
        let n = 65;
        let mut line = Line::new(n, 0.0);
        let mid = (n / 2) as f64;
        for q in 0..n {
            let t = (q as f64 - mid) / mid;
            line.d0[2 * q] = -1.0 - 0.5 * t * t;
            line.d0[2 * q + 1] = 0.6 * t;
        }
        // S and C as the condensed path keeps them: their upper triangles packed
        let dim = 2 * n;
        let parts = StiffParts::of(&line);
        let st = parts.stiff();
        let c_packed = pack_upper(line.cmat.as_slice().to_vec(), dim);
        let dual = line.dense(100.0);
        let primal = DenseIteration {
            cmat: CMatrix::Upper {
                n: dim,
                packed: &c_packed,
            },
            stiff: Some(&st),
            ..dual
        };
        let dual_packed = DenseIteration {
            stiff: None,
            ..primal
        };
        let (start, u_prev) = dual.frictionless_start(&vec![true; n], &vec![0.0; n]);
        let a = dual.run(&start, u_prev.clone());
        let b = primal.run(&start, u_prev.clone());
        let c = dual_packed.run(&start, u_prev);
        assert!(c.end.is_ok(), "{:?}", c.end);
        assert_eq!(
            (c.active.clone(), c.slip.clone()),
            (a.active.clone(), a.slip.clone())
        );
        let scale = a.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (x, y) in a.lambda.iter().zip(&c.lambda) {
            assert!((x - y).abs() <= 1e-12 * scale, "the packed C: {x} {y}");
        }
        assert!(a.end.is_ok() && b.end.is_ok(), "{:?} {:?}", a.end, b.end);
        assert_eq!((a.primal_steps, b.primal_steps), (0, b.steps.len()));
        let slips = (0..n).filter(|&q| b.active[q] && b.slip[q]).count();
        let sticks = (0..n).filter(|&q| b.active[q] && !b.slip[q]).count();
        assert!(slips > 5 && sticks > 5, "{slips} slip, {sticks} stick");
        assert_eq!((a.active.clone(), a.slip.clone()), (b.active, b.slip));
        let scale = a.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (x, y) in a.lambda.iter().zip(&b.lambda) {
            assert!((x - y).abs() <= 1e-10 * scale, "{x} {y}");
        }
        // the primal iterate's own u − G α: the dual's d₀ − C λ
        let w = DVector::from_column_slice(&line.d0)
            - &line.cmat * DVector::from_column_slice(&a.lambda);
        let wmax = w.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (x, y) in w.iter().zip(&b.x_s) {
            assert!((x - y).abs() <= 1e-10 * wmax, "{x} {y}");
        }
    });
}

#[test]
fn a_system_that_holds_at_the_iterate_is_a_fixed_point() {
    // rows as columns: [[2, 1], [0, 4]] x = [3, 4] ⇒ x = (1, 1)
    let sys = |a: [[f64; 2]; 2], b: [f64; 2]| System {
        a: DMatrix::from_fn(2, 2, |j, i| a[i][j]),
        rhs: DVector::from_row_slice(&b),
        cols: vec![Unknown { dof: 0, tied: None }],
        known: None,
        zero: Vec::new(),
        given: Vec::new(),
        alpha_scale: 1.0,
    };
    let own = sys([[2.0, 1.0], [0.0, 4.0]], [3.0, 4.0]);
    let x = [1.0, 1.0 + 2.0 * f64::EPSILON];
    let r = residual_at(&own, &x);
    assert!(r > 0.0 && r < 1e-14, "{r}");
    // the same rows: a fixed point; one row scaled: still (it holds at x)
    assert!(fixed_point(&own, &x, r));
    assert!(fixed_point(
        &sys([[2.0, 1.0], [0.0, 8.0]], [3.0, 8.0]),
        &x,
        r
    ));
    // a row that changed beyond round-off at x: not
    assert!(!fixed_point(
        &sys([[2.0, 1.0], [0.0, 4.0]], [3.0, 4.0 + 1e-9]),
        &x,
        r
    ));
    assert!(!fixed_point(
        &sys([[2.0, 1.1], [0.0, 4.0]], [3.0, 4.0]),
        &x,
        r
    ));
}

/// The settled rows (docs/friction.md, "Settled slip") against the (F5) rows throughout, on
/// the pushed line with c = 100 and a push under which every active node but one slips far
/// beyond its threshold: the same solution, in fewer fine steps after the nested start.
#[test]
fn settled_rows_end_a_wide_slip_in_fewer_steps() {
    on_big_stack(|| {
        let n = 129;
        let line = Line::new(n, 0.3);
        let settled = line.dense(100.0);
        let f5 = DenseIteration {
            settle: false,
            ..settled
        };
        let active: Vec<bool> = (0..n).map(|i| i == n / 2).collect();
        let (start, u_prev) = settled.frictionless_start(&active, &vec![0.0; n]);
        let a = settled.run_nested(&start, u_prev.clone());
        let b = f5.run_nested(&start, u_prev);
        assert!(a.end.is_ok() && b.end.is_ok(), "{:?} {:?}", a.end, b.end);
        let slips = (0..n).filter(|&q| a.active[q] && a.slip[q]).count();
        assert!(slips > 50, "{slips} slipping");
        let scale = b.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        // A node on its stick/slip threshold to round-off (|λ_τ| = μ|λ_n|) solves the
        // problem in either state, so its state is decided by the BLAS kernels' round-off
        // (measured: the middle node sticks with OpenBLAS' Prescott and Haswell kernels and
        // slips with SkylakeX and Nehalem): its state is not compared, its λ is.
        let at_limit = |r: &DenseCoulomb, q: usize| {
            (r.lambda[2 * q + 1].abs() - 0.3 * r.lambda[2 * q].abs()).abs() <= 1e-8 * scale
        };
        for q in 0..n {
            assert_eq!(a.active[q], b.active[q], "node {q}");
            if !(at_limit(&a, q) && at_limit(&b, q)) {
                assert_eq!(a.slip[q], b.slip[q], "node {q}");
            }
        }
        for (x, y) in a.lambda.iter().zip(&b.lambda) {
            assert!((x - y).abs() <= 1e-10 * scale, "{x} {y}");
        }
        assert!(
            a.steps.len() < b.steps.len(),
            "fine steps: settled {}, (F5) rows {}",
            a.steps.len(),
            b.steps.len()
        );
    });
}

fn nested_against_plain() {
    let n = 129;
    let line = Line::new(n, 0.1);
    let dense = line.dense(1.0);
    // the frictionless start: the middle node touching, λ = 0
    let active: Vec<bool> = (0..n).map(|i| i == n / 2).collect();
    let (start, u_prev) = dense.frictionless_start(&active, &vec![0.0; n]);
    let plain = dense.run(&start, u_prev.clone());
    let nested = dense.run_nested(&start, u_prev);
    assert!(
        plain.end.is_ok() && nested.end.is_ok(),
        "{:?} {:?}",
        plain.end,
        nested.end
    );
    let (slips, sticks) = (0..n)
        .filter(|&q| plain.active[q])
        .fold((0, 0), |(s, k), q| {
            if plain.slip[q] {
                (s + 1, k)
            } else {
                (s, k + 1)
            }
        });
    assert!(
        slips > 0 && sticks > 0,
        "partial slip: {slips} slip, {sticks} stick"
    );
    let scale = plain.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for (a, b) in nested.lambda.iter().zip(&plain.lambda) {
        assert!((a - b).abs() <= 1e-10 * scale, "{a} {b}");
    }
    assert!(!nested.coarse.is_empty());
    assert!(
        nested.steps.len() < plain.steps.len(),
        "fine steps: nested {} plain {}",
        nested.steps.len(),
        plain.steps.len()
    );
}

/// Tresca (3.18) on the line: every node has the threshold b_k = 0.05, in contact or not. The
/// middle is pressed (d₀ < 0), the ends lift off (d₀ > 0) and are pushed sideways both ways, so
/// nodes out of contact stick (S1) and slip (S2) with λ_τ ≠ 0. The dual and the primal form, with
/// and without the settled rows, end in the same states and λ, and the end holds Tresca's law
/// node by node.
#[test]
fn tresca_out_of_contact_ends_in_the_same_state_in_every_form() {
    on_big_stack(|| {
        let n = 41;
        let b = 0.05;
        let mut line = Line::new(n, 0.0);
        let mid = (n / 2) as f64;
        for q in 0..n {
            let t = (q as f64 - mid) / mid;
            line.d0[2 * q] = -0.5 + 1.5 * t * t;
            line.d0[2 * q + 1] = 0.4 * t * t * t;
            line.cb.nodes[q].bound = b;
        }
        let parts = StiffParts::of(&line);
        let st = parts.stiff();
        let base = || DenseIteration {
            law: Law::Tresca,
            ..line.dense(1.0)
        };
        let runs = [
            base(),
            DenseIteration {
                stiff: Some(&st),
                ..base()
            },
            DenseIteration {
                settle: false,
                ..base()
            },
        ];
        let (start, u_prev) = base().frictionless_start(&vec![true; n], &vec![0.0; n]);
        let ends: Vec<DenseCoulomb> = runs.iter().map(|d| d.run(&start, u_prev.clone())).collect();
        for e in &ends {
            assert!(e.end.is_ok(), "{:?}", e.end);
        }
        let a = &ends[0];
        let out_stick = (0..n).filter(|&q| !a.active[q] && !a.slip[q]).count();
        let out_slip = (0..n).filter(|&q| !a.active[q] && a.slip[q]).count();
        let in_contact = (0..n).filter(|&q| a.active[q]).count();
        assert!(
            out_stick > 0 && out_slip > 0 && in_contact > 0,
            "{in_contact} in contact, {out_stick} S1, {out_slip} S2"
        );
        let scale = a.lambda.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for e in &ends[1..] {
            assert_eq!((&e.active, &e.slip), (&a.active, &a.slip));
            for (x, y) in a.lambda.iter().zip(&e.lambda) {
                assert!((x - y).abs() <= 1e-10 * scale, "{x} {y}");
            }
        }
        // Tresca's law at the end: u = d₀ − C λ
        let u = DVector::from_column_slice(&line.d0)
            - &line.cmat * DVector::from_column_slice(&a.lambda);
        let umax = u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for q in 0..n {
            let (un, ut, ln, lt) = (u[2 * q], u[2 * q + 1], a.lambda[2 * q], a.lambda[2 * q + 1]);
            if a.active[q] {
                assert!(un.abs() <= 1e-12 * umax && ln <= 1e-12 * scale, "node {q}");
            } else {
                assert!(un >= -1e-12 * umax && ln == 0.0, "node {q}: {un} {ln}");
            }
            assert!(lt.abs() <= b * (1.0 + 1e-10), "node {q}: |λ_τ| {lt}");
            if a.slip[q] {
                assert!(
                    (lt - b * ut.signum()).abs() <= 1e-10 * b,
                    "node {q}: {lt} {ut}"
                );
            } else {
                assert!(ut.abs() <= 1e-12 * umax, "node {q}: u_τ {ut}");
            }
        }
    });
}

#[test]
fn steps_that_hold_a_free_mode_by_no_row_and_change_nothing_end_the_run_at_once() {
    on_big_stack(|| {
        // the line lifted off the obstacle (d₀ = 0.5 along every normal), free to move along
        // the normal (one free mode, normal part 1 at every node) and pushed onto it by a
        // load in that mode: from a start with nothing in contact no row holds the mode, each
        // step is solved with α pinned at 0, so u stays d₀ and no node comes into contact
        let n = 9;
        let mut line = Line::new(n, 0.0);
        for r in (0..2 * n).step_by(2) {
            line.d0[r] = 0.5;
        }
        line.g = DMatrix::from_fn(2 * n, 1, |r, _| if r % 2 == 0 { 1.0 } else { 0.0 });
        let phi = [1.0];
        let dense = DenseIteration {
            phi: &phi,
            ..line.dense(1.0)
        };
        let (start, u_prev) = dense.frictionless_start(&vec![false; n], &vec![0.0; n]);
        let run = dense.run(&start, u_prev);
        let why = run.end.clone().expect_err("no accepted iterate");
        assert!(why.contains("by no row"), "{why}");
        assert!(
            run.steps.len() <= STUCK_PINNED + 1,
            "{} steps: {why}",
            run.steps.len()
        );
    });
}
