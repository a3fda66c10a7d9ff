//! Unit tests of the P1 kernels. Expected values come from textbook formulas written out
//! independently here (Voigt B^T D B with engineering constants, classic CST coefficients,
//! strain energy, exact simplex integrals), never from the code under test.

// Index loops mirror the tensor formulas (sums over i, j, a, b).
#![allow(clippy::needless_range_loop)]

use super::*;
use nalgebra::DMatrix;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn mat(young: f64, poisson: f64, model: Model) -> Material {
    Material {
        young,
        poisson,
        model,
    }
}

/// Dense C = A^T D A for row-major A (r x c) and D (r x r).
fn btdb(b: &[f64], d: &[f64], r: usize, c: usize) -> Vec<f64> {
    let mut out = vec![0.0; c * c];
    for i in 0..c {
        for j in 0..c {
            let mut s = 0.0;
            for p in 0..r {
                for q in 0..r {
                    s += b[p * c + i] * d[p * r + q] * b[q * c + j];
                }
            }
            out[i * c + j] = s;
        }
    }
    out
}

/// Textbook plane strain / plane stress elasticity matrix for (eps_xx, eps_yy, gamma_xy).
fn d_plane(e: f64, nu: f64, model: Model) -> [f64; 9] {
    match model {
        Model::PlaneStrain => {
            let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            [
                f * (1.0 - nu),
                f * nu,
                0.0,
                f * nu,
                f * (1.0 - nu),
                0.0,
                0.0,
                0.0,
                f * (1.0 - 2.0 * nu) / 2.0,
            ]
        }
        Model::PlaneStress => {
            let f = e / (1.0 - nu * nu);
            [
                f,
                f * nu,
                0.0,
                f * nu,
                f,
                0.0,
                0.0,
                0.0,
                f * (1.0 - nu) / 2.0,
            ]
        }
        Model::Solid => unreachable!(),
    }
}

/// Textbook 3D elasticity matrix for (xx, yy, zz, gamma_yz, gamma_xz, gamma_xy).
fn d_solid(e: f64, nu: f64) -> [f64; 36] {
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let a = f * (1.0 - nu);
    let b = f * nu;
    let g = e / (2.0 * (1.0 + nu));
    [
        a, b, b, 0.0, 0.0, 0.0, //
        b, a, b, 0.0, 0.0, 0.0, //
        b, b, a, 0.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, g, 0.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, g, 0.0, //
        0.0, 0.0, 0.0, 0.0, 0.0, g, //
    ]
}

/// Classic constant-strain-triangle B (3 x 6) and area: b_i = y_j - y_k, c_i = x_k - x_j.
fn cst_b(x: &[[f64; 2]; 3]) -> ([f64; 18], f64) {
    let two_a =
        (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
    let mut b = [0.0; 18];
    for i in 0..3 {
        let j = (i + 1) % 3;
        let k = (i + 2) % 3;
        let bi = (x[j][1] - x[k][1]) / two_a;
        let ci = (x[k][0] - x[j][0]) / two_a;
        b[2 * i] = bi; // eps_xx row
        b[6 + 2 * i + 1] = ci; // eps_yy row
        b[12 + 2 * i] = ci; // gamma_xy row
        b[12 + 2 * i + 1] = bi;
    }
    (b, two_a / 2.0)
}

fn random_tri(rng: &mut StdRng) -> [[f64; 2]; 3] {
    let mut x = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    for p in x.iter_mut() {
        for c in p.iter_mut() {
            *c += rng.gen_range(-0.3..0.3);
        }
    }
    x
}

fn random_tet(rng: &mut StdRng) -> [[f64; 3]; 4] {
    let mut x = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    for p in x.iter_mut() {
        for c in p.iter_mut() {
            *c += rng.gen_range(-0.25..0.25);
        }
    }
    x
}

fn numerical_rank(k: &[f64], n: usize) -> usize {
    let m = DMatrix::from_row_slice(n, n, k);
    let ev = m.symmetric_eigen().eigenvalues;
    let max = ev.iter().fold(0.0f64, |a, &v| a.max(v.abs()));
    ev.iter().filter(|v| v.abs() > 1e-10 * max).count()
}

// ---------------------------------------------------------------- material

#[test]
fn lame_plane_strain_and_solid() {
    // E = 2, nu = 0.3 (the thesis' disk): lambda = 0.6 / (1.3 * 0.4), mu = 2 / 2.6.
    for model in [Model::PlaneStrain, Model::Solid] {
        let (l, m) = mat(2.0, 0.3, model).lame();
        assert!(close(l, 1.153_846_153_846_154, 1e-14), "{l}");
        assert!(close(m, 0.769_230_769_230_769_2, 1e-14), "{m}");
    }
}

#[test]
fn lame_plane_stress() {
    // E = 1, nu = 0.25: lambda = 0.25 / 0.9375 = 4/15, mu = 1 / 2.5 = 0.4.
    let (l, m) = mat(1.0, 0.25, Model::PlaneStress).lame();
    assert!(close(l, 4.0 / 15.0, 1e-14), "{l}");
    assert!(close(m, 0.4, 1e-14), "{m}");
}

#[test]
fn plane_stress_is_plane_strain_with_modified_constants() {
    for &(e, nu) in &[
        (1.0, 0.0),
        (2.0, 0.3),
        (210e9, 0.29),
        (5.0, 0.49),
        (1.0, -0.3),
    ] {
        let ps = mat(e, nu, Model::PlaneStress).lame();
        let es = e * (1.0 + 2.0 * nu) / ((1.0 + nu) * (1.0 + nu));
        let nus = nu / (1.0 + nu);
        let pe = mat(es, nus, Model::PlaneStrain).lame();
        assert!(close(ps.0, pe.0, 1e-13), "lambda {ps:?} {pe:?}");
        assert!(close(ps.1, pe.1, 1e-13), "mu {ps:?} {pe:?}");
    }
}

#[test]
fn model_dimensions() {
    assert_eq!(Model::PlaneStrain.dim(), 2);
    assert_eq!(Model::PlaneStress.dim(), 2);
    assert_eq!(Model::Solid.dim(), 3);
}

// ---------------------------------------------------------------- triangle

#[test]
fn tri_reference_e1_nu0_by_hand() {
    // E = 1, nu = 0: lambda = 0, mu = 1/2, D = diag(1, 1, 1/2), area 1/2, gradients
    // (-1,-1), (1,0), (0,1). K = 1/2 B^T D B worked out on paper:
    #[rustfmt::skip]
    let expected = [
         0.75,  0.25, -0.5, -0.25, -0.25,  0.0,
         0.25,  0.75,  0.0, -0.25, -0.25, -0.5,
        -0.5,   0.0,   0.5,  0.0,   0.0,   0.0,
        -0.25, -0.25,  0.0,  0.25,  0.25,  0.0,
        -0.25, -0.25,  0.0,  0.25,  0.25,  0.0,
         0.0,  -0.5,   0.0,  0.0,   0.0,   0.5,
    ];
    let (l, m) = mat(1.0, 0.0, Model::PlaneStrain).lame();
    let mut k = [0.0; 36];
    let area = tri_stiffness(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], l, m, &mut k);
    assert_eq!(area, 0.5);
    for i in 0..36 {
        assert!(
            close(k[i], expected[i], 1e-15),
            "entry {i}: {} vs {}",
            k[i],
            expected[i]
        );
    }
}

#[test]
fn tri_matches_voigt_btdb() {
    let mut rng = StdRng::seed_from_u64(7);
    let mut cells = vec![[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
    for _ in 0..5 {
        cells.push(random_tri(&mut rng));
    }
    for model in [Model::PlaneStrain, Model::PlaneStress] {
        for &(e, nu) in &[(1.0, 0.0), (1.0, 0.3), (2.0, 0.3), (7.5, 0.45)] {
            for x in &cells {
                let (b, area) = cst_b(x);
                let d = d_plane(e, nu, model);
                let mut expected = btdb(&b, &d, 3, 6);
                expected.iter_mut().for_each(|v| *v *= area);
                let (l, m) = mat(e, nu, model).lame();
                let mut k = [0.0; 36];
                let a = tri_stiffness(x, l, m, &mut k);
                assert!(close(a, area, 1e-14));
                let scale = expected.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                for i in 0..36 {
                    assert!(
                        (k[i] - expected[i]).abs() <= 1e-13 * scale,
                        "{model:?} E={e} nu={nu} entry {i}: {} vs {}",
                        k[i],
                        expected[i]
                    );
                }
            }
        }
    }
}

#[test]
fn tri_symmetric_rigid_modes_rank() {
    let mut rng = StdRng::seed_from_u64(11);
    for _ in 0..20 {
        let x = random_tri(&mut rng);
        let mut k = [0.0; 36];
        tri_stiffness(&x, 1.3, 0.7, &mut k);
        let scale = k.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for i in 0..6 {
            for j in 0..6 {
                assert!((k[i * 6 + j] - k[j * 6 + i]).abs() <= 1e-14 * scale);
            }
        }
        for mode in 0..n_rigid_modes(2) {
            let mut r = [0.0; 6];
            for a in 0..3 {
                let v = rigid_mode(2, mode, [x[a][0], x[a][1], 0.0]);
                r[2 * a] = v[0];
                r[2 * a + 1] = v[1];
            }
            let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            for i in 0..6 {
                let kr: f64 = (0..6).map(|j| k[i * 6 + j] * r[j]).sum();
                assert!(kr.abs() <= 1e-12 * scale * rn, "mode {mode}: {kr}");
            }
        }
        assert_eq!(numerical_rank(&k, 6), 3);
    }
}

#[test]
fn tri_orientation_and_degenerate() {
    let ccw = [[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
    let cw = [[0.0, 0.0], [0.0, 1.0], [2.0, 0.0]];
    let mut k1 = [0.0; 36];
    let mut k2 = [0.0; 36];
    assert_eq!(tri_stiffness(&ccw, 1.0, 1.0, &mut k1), 1.0);
    assert_eq!(tri_stiffness(&cw, 1.0, 1.0, &mut k2), -1.0);
    // Same element with nodes 1 and 2 swapped: permuted matrix, same values.
    let perm = [0, 2, 1];
    for a in 0..3 {
        for b in 0..3 {
            for i in 0..2 {
                for j in 0..2 {
                    let v1 = k1[(2 * a + i) * 6 + 2 * b + j];
                    let v2 = k2[(2 * perm[a] + i) * 6 + 2 * perm[b] + j];
                    assert!(close(v1, v2, 1e-15));
                }
            }
        }
    }
    let mut k = [1.0; 36];
    let area = tri_stiffness(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]], 1.0, 1.0, &mut k);
    assert_eq!(area, 0.0);
    assert!(k.iter().all(|&v| v == 0.0));
}

// ---------------------------------------------------------------- tetrahedron

#[test]
fn tet_reference_matches_voigt_btdb() {
    // Reference tet: gradients (-1,-1,-1), e1, e2, e3; volume 1/6.
    let g = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    // B rows: xx, yy, zz, gamma_yz, gamma_xz, gamma_xy.
    let mut b = [0.0; 72];
    for a in 0..4 {
        let c = 3 * a;
        b[c] = g[a][0];
        b[12 + c + 1] = g[a][1];
        b[24 + c + 2] = g[a][2];
        b[36 + c + 1] = g[a][2];
        b[36 + c + 2] = g[a][1];
        b[48 + c] = g[a][2];
        b[48 + c + 2] = g[a][0];
        b[60 + c] = g[a][1];
        b[60 + c + 1] = g[a][0];
    }
    let x = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    for &(e, nu) in &[(1.0, 0.0), (1.0, 0.25), (3.0, 0.4)] {
        let mut expected = btdb(&b, &d_solid(e, nu), 6, 12);
        expected.iter_mut().for_each(|v| *v /= 6.0);
        let (l, m) = mat(e, nu, Model::Solid).lame();
        let mut k = [0.0; 144];
        let vol = tet_stiffness(&x, l, m, &mut k);
        assert!(close(vol, 1.0 / 6.0, 1e-15));
        for i in 0..144 {
            assert!(close(k[i], expected[i], 1e-14), "E={e} nu={nu} entry {i}");
        }
    }
    // Two entries by hand for E = 1, nu = 0 (lambda = 0, mu = 1/2):
    // K[x0,x0] = V (mu |g0|^2 + mu g0x^2) = (1/6)(3/2 + 1/2) = 1/3,
    // K[x0,y1] = V (lambda g0x g1y + mu g0y g1x) = (1/6)(1/2)(-1)(1) = -1/12.
    let mut k = [0.0; 144];
    tet_stiffness(&x, 0.0, 0.5, &mut k);
    assert!(close(k[0], 1.0 / 3.0, 1e-15));
    assert!(close(k[3 + 1], -1.0 / 12.0, 1e-15));
}

#[test]
fn tet_symmetric_rigid_modes_rank() {
    let mut rng = StdRng::seed_from_u64(13);
    for _ in 0..20 {
        let x = random_tet(&mut rng);
        let mut k = [0.0; 144];
        tet_stiffness(&x, 2.1, 0.9, &mut k);
        let scale = k.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for i in 0..12 {
            for j in 0..12 {
                assert!((k[i * 12 + j] - k[j * 12 + i]).abs() <= 1e-14 * scale);
            }
        }
        for mode in 0..n_rigid_modes(3) {
            let mut r = [0.0; 12];
            for a in 0..4 {
                let v = rigid_mode(3, mode, x[a]);
                r[3 * a..3 * a + 3].copy_from_slice(&v);
            }
            let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            for i in 0..12 {
                let kr: f64 = (0..12).map(|j| k[i * 12 + j] * r[j]).sum();
                assert!(kr.abs() <= 1e-12 * scale * rn, "mode {mode}: {kr}");
            }
        }
        assert_eq!(numerical_rank(&k, 12), 6);
    }
}

#[test]
fn tet_orientation_and_degenerate() {
    let x = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 3.0],
    ];
    let mut k = [0.0; 144];
    assert!(close(tet_stiffness(&x, 1.0, 1.0, &mut k), 1.0, 1e-15));
    let y = [x[0], x[2], x[1], x[3]];
    assert!(close(tet_stiffness(&y, 1.0, 1.0, &mut k), -1.0, 1e-15));
    let flat = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let mut k = [1.0; 144];
    assert_eq!(tet_stiffness(&flat, 1.0, 1.0, &mut k), 0.0);
    assert!(k.iter().all(|&v| v == 0.0));
}

/// u^T K u = 2 |T| W(eps) for the interpolant of a linear field u = G x + c, with the strain
/// energy density W = lambda/2 tr(eps)^2 + mu eps:eps. Includes negatively oriented cells.
#[test]
fn energy_of_linear_fields() {
    let mut rng = StdRng::seed_from_u64(17);
    let (l, m) = (1.7, 0.6);
    for trial in 0..20 {
        let mut gm = [[0.0; 3]; 3];
        for row in gm.iter_mut() {
            for v in row.iter_mut() {
                *v = rng.gen_range(-1.0..1.0);
            }
        }
        let c: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
        let energy = |d: usize| {
            let mut tr = 0.0;
            let mut ee = 0.0;
            for i in 0..d {
                tr += gm[i][i];
                for j in 0..d {
                    let e = 0.5 * (gm[i][j] + gm[j][i]);
                    ee += e * e;
                }
            }
            0.5 * l * tr * tr + m * ee
        };
        // triangle
        let mut x = random_tri(&mut rng);
        if trial % 2 == 1 {
            x.swap(1, 2);
        }
        let mut u = [0.0; 6];
        for a in 0..3 {
            for i in 0..2 {
                u[2 * a + i] = gm[i][0] * x[a][0] + gm[i][1] * x[a][1] + c[i];
            }
        }
        let mut k = [0.0; 36];
        let area = tri_stiffness(&x, l, m, &mut k).abs();
        let uku: f64 = (0..6)
            .flat_map(|i| (0..6).map(move |j| (i, j)))
            .map(|(i, j)| u[i] * k[i * 6 + j] * u[j])
            .sum();
        assert!(close(uku, 2.0 * area * energy(2), 1e-12), "tri {uku}");
        // tetrahedron
        let mut x = random_tet(&mut rng);
        if trial % 2 == 1 {
            x.swap(0, 3);
        }
        let mut u = [0.0; 12];
        for a in 0..4 {
            for i in 0..3 {
                u[3 * a + i] = gm[i][0] * x[a][0] + gm[i][1] * x[a][1] + gm[i][2] * x[a][2] + c[i];
            }
        }
        let mut k = [0.0; 144];
        let vol = tet_stiffness(&x, l, m, &mut k).abs();
        let uku: f64 = (0..12)
            .flat_map(|i| (0..12).map(move |j| (i, j)))
            .map(|(i, j)| u[i] * k[i * 12 + j] * u[j])
            .sum();
        assert!(close(uku, 2.0 * vol * energy(3), 1e-12), "tet {uku}");
    }
}

// ---------------------------------------------------------------- stress

#[test]
fn linear_field_gives_constant_stress() {
    let mut rng = StdRng::seed_from_u64(19);
    let (e, nu) = (3.0, 0.3);
    let gm = [
        [0.01, 0.02, -0.005],
        [-0.015, 0.03, 0.007],
        [0.004, -0.002, 0.02],
    ];
    // 2D: textbook sigma = D (eps_xx, eps_yy, gamma_xy).
    let strain2 = [gm[0][0], gm[1][1], gm[0][1] + gm[1][0]];
    for model in [Model::PlaneStrain, Model::PlaneStress] {
        let d = d_plane(e, nu, model);
        let sig: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|c| d[r * 3 + c] * strain2[c]).sum())
            .collect();
        let x2 = random_tri(&mut rng);
        let x: Vec<[f64; 3]> = x2.iter().map(|p| [p[0], p[1], 99.0]).collect();
        let mut u = vec![0.0; 6];
        for a in 0..3 {
            for i in 0..2 {
                u[2 * a + i] = gm[i][0] * x[a][0] + gm[i][1] * x[a][1] + 0.3;
            }
        }
        let s = cell_stress(&mat(e, nu, model), &x, &u);
        assert!(close(s[0][0], sig[0], 1e-12), "{model:?}");
        assert!(close(s[1][1], sig[1], 1e-12), "{model:?}");
        assert!(close(s[0][1], sig[2], 1e-12), "{model:?}");
        assert!(close(s[1][0], sig[2], 1e-12), "{model:?}");
        assert_eq!(s[0][2], 0.0);
        assert_eq!(s[2][1], 0.0);
        let szz = if model == Model::PlaneStrain {
            nu * (sig[0] + sig[1]) // eps_zz = 0 in Hooke's law with E, nu
        } else {
            0.0
        };
        assert!(close(s[2][2], szz, 1e-12), "{model:?} szz {}", s[2][2]);
    }
    // 3D.
    let strain3 = [
        gm[0][0],
        gm[1][1],
        gm[2][2],
        gm[1][2] + gm[2][1],
        gm[0][2] + gm[2][0],
        gm[0][1] + gm[1][0],
    ];
    let d = d_solid(e, nu);
    let sig: Vec<f64> = (0..6)
        .map(|r| (0..6).map(|c| d[r * 6 + c] * strain3[c]).sum())
        .collect();
    let x = random_tet(&mut rng);
    let mut u = vec![0.0; 12];
    for a in 0..4 {
        for i in 0..3 {
            u[3 * a + i] = (0..3).map(|j| gm[i][j] * x[a][j]).sum::<f64>() - 0.1;
        }
    }
    let s = cell_stress(&mat(e, nu, Model::Solid), &x, &u);
    let idx = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)];
    for (v, &(i, j)) in idx.iter().enumerate() {
        assert!(close(s[i][j], sig[v], 1e-12), "{i}{j}");
        assert!(close(s[j][i], sig[v], 1e-12), "{j}{i}");
    }
}

#[test]
fn von_mises_standard_cases() {
    for sv in [2.5, -4.0] {
        let mut s = [[0.0; 3]; 3];
        s[1][1] = sv;
        assert!(close(von_mises(&s), sv.abs(), 1e-15));
    }
    let t = -1.5;
    let s = [[0.0, t, 0.0], [t, 0.0, 0.0], [0.0, 0.0, 0.0]];
    assert!(close(von_mises(&s), 3f64.sqrt() * t.abs(), 1e-15));
    let p = 7.0;
    let s = [[p, 0.0, 0.0], [0.0, p, 0.0], [0.0, 0.0, p]];
    assert!(von_mises(&s).abs() < 1e-14);
    // Principal stresses 1, 2, 4: sqrt(((1-2)^2 + (2-4)^2 + (4-1)^2) / 2) = sqrt(7).
    let s = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 4.0]];
    assert!(close(von_mises(&s), 7f64.sqrt(), 1e-15));
}

#[test]
fn von_mises_thesis_cases() {
    // 2D: a = 3, b = 1, c = -1, p = 1: (3-1)^2 + (-1-1)^2 + 2 * 1^2 = 10; sigma_zz ignored.
    let s = [[3.0, 1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 0.0, 7.0]];
    assert!(close(von_mises_thesis(&s, 2), 10f64.sqrt(), 1e-15));
    // 2D uniaxial s: p = s/2, sum = 2 (s/2)^2 -> |s| / sqrt 2.
    let s = [[4.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
    assert!(close(von_mises_thesis(&s, 2), 4.0 / 2f64.sqrt(), 1e-15));
    // 3D uniaxial s: p = s/3, sum = (2s/3)^2 + 2 (s/3)^2 = 2/3 s^2.
    assert!(close(
        von_mises_thesis(&s, 3),
        4.0 * (2.0f64 / 3.0).sqrt(),
        1e-15
    ));
    // In 3D it is the deviatoric norm: sqrt(2/3) times the standard von Mises.
    let s = [[1.0, 0.3, -0.2], [0.3, -2.0, 0.5], [-0.2, 0.5, 0.7]];
    assert!(close(
        von_mises_thesis(&s, 3),
        (2.0f64 / 3.0).sqrt() * von_mises(&s),
        1e-14
    ));
}

// ---------------------------------------------------------------- loads

#[test]
fn facet_normals() {
    let (n, len) = facet_normal_measure(&[[0.0, 0.0, 5.0], [2.0, 0.0, -1.0]]);
    assert_eq!(len, 2.0);
    assert_eq!(n, [0.0, -1.0, 0.0]);
    let (n, len) = facet_normal_measure(&[[1.0, 1.0, 0.0], [0.0, 2.0, 0.0]]);
    assert!(close(len, 2f64.sqrt(), 1e-15));
    let h = 0.5f64.sqrt();
    assert!(close(n[0], h, 1e-15) && close(n[1], h, 1e-15));
    // Outward on every edge of a counter-clockwise triangle.
    let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.2, 0.9, 0.0]];
    let cen = [0.4, 0.3];
    for e in 0..3 {
        let (a, b) = (t[e], t[(e + 1) % 3]);
        let (n, _) = facet_normal_measure(&[a, b]);
        let out = (a[0] - cen[0]) * n[0] + (a[1] - cen[1]) * n[1];
        assert!(out > 0.0, "edge {e}");
    }
    // 3D: xy triangle, right-hand rule.
    let (n, area) = facet_normal_measure(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    assert_eq!(n, [0.0, 0.0, 1.0]);
    assert_eq!(area, 0.5);
    // Outward on the faces of a positively oriented tet listed (1,2,3), (0,3,2), (0,1,3), (0,2,1).
    let x = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let cen = [0.25, 0.25, 0.25];
    for f in [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]] {
        let (n, area) = facet_normal_measure(&[x[f[0]], x[f[1]], x[f[2]]]);
        let p = x[f[0]];
        let out: f64 = (0..3).map(|c| (p[c] - cen[c]) * n[c]).sum();
        assert!(out > 0.0, "face {f:?}");
        assert!(close((0..3).map(|c| n[c] * n[c]).sum::<f64>(), 1.0, 1e-15));
        let expected = if f == [1, 2, 3] {
            3f64.sqrt() / 2.0
        } else {
            0.5
        };
        assert!(close(area, expected, 1e-15));
    }
    let (n, m) = facet_normal_measure(&[[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]);
    assert_eq!((n, m), ([0.0; 3], 0.0));
}

#[test]
fn lumped_loads_sum_to_total() {
    let t = [0.3, -0.02, 1.5];
    for dim in [2usize, 3] {
        let mut out = vec![f64::NAN; dim * dim];
        lumped_facet_load(0.7, t, dim, &mut out);
        for i in 0..dim {
            let s: f64 = (0..dim).map(|a| out[a * dim + i]).sum();
            assert!(close(s, t[i] * 0.7, 1e-15));
            for a in 0..dim {
                assert!(close(out[a * dim + i], t[i] * 0.7 / dim as f64, 1e-15));
            }
        }
        let mut out = vec![f64::NAN; (dim + 1) * dim];
        body_force_load(2.0, t, dim, &mut out);
        for i in 0..dim {
            let s: f64 = (0..=dim).map(|a| out[a * dim + i]).sum();
            assert!(close(s, t[i] * 2.0, 1e-15));
        }
    }
}

#[test]
fn quadrature_rules_constants() {
    let s3 = 3f64.sqrt();
    let s5 = 5f64.sqrt();
    let line = simplex_quadrature(2);
    assert!(close(line[0].bary[0], (1.0 + 1.0 / s3) / 2.0, 1e-15));
    assert!(close(line[0].bary[1], (1.0 - 1.0 / s3) / 2.0, 1e-15));
    let tet = simplex_quadrature(4);
    assert!(close(tet[0].bary[0], (5.0 + 3.0 * s5) / 20.0, 1e-15));
    assert!(close(tet[0].bary[1], (5.0 - s5) / 20.0, 1e-15));
    for n in 2..=4 {
        let r = simplex_quadrature(n);
        assert!(close(r.iter().map(|q| q.weight).sum::<f64>(), 1.0, 1e-15));
        for q in r {
            assert!(close(q.bary.iter().sum::<f64>(), 1.0, 1e-15));
        }
    }
}

/// Simplices used for the quadrature tests: (vertices, dim).
fn quad_cases(rng: &mut StdRng) -> Vec<(Vec<[f64; 3]>, usize)> {
    let mut r = |s: f64| rng.gen_range(-s..s);
    vec![
        // segment in 2D (z garbage, must be ignored)
        (vec![[0.1, 0.2, 3.0], [1.3 + r(0.2), -0.4, -2.0]], 2),
        // segment in 3D
        (vec![[0.1, 0.2, 0.3], [1.0, r(1.0), 0.7]], 3),
        // triangle cell in 2D
        (
            vec![[0.0, 0.0, 0.0], [1.2, r(0.3), 0.0], [r(0.3), 0.9, 0.0]],
            2,
        ),
        // triangle facet in 3D
        (
            vec![[0.0, 0.1, 0.2], [1.0, r(0.3), 0.5], [r(0.3), 0.8, 1.1]],
            3,
        ),
        // tetrahedron
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, r(0.2), r(0.2)],
                [r(0.2), 1.1, r(0.2)],
                [r(0.2), r(0.2), 0.9],
            ],
            3,
        ),
    ]
}

/// ∫_T λ_a λ_b = |T| (1 + δ_ab) n! / (n+2)! on an n-simplex.
fn mass_factor(nverts: usize, a: usize, b: usize) -> f64 {
    let n = nverts - 1;
    let base = match n {
        1 => 1.0 / 6.0,
        2 => 1.0 / 12.0,
        3 => 1.0 / 20.0,
        _ => unreachable!(),
    };
    if a == b {
        2.0 * base
    } else {
        base
    }
}

#[test]
fn quadrature_load_exact_for_linear_fields() {
    let mut rng = StdRng::seed_from_u64(23);
    let lin = |p: [f64; 3]| {
        [
            1.0 + 2.0 * p[0] - p[1] + 0.5 * p[2],
            -0.3 + p[1] + 4.0 * p[2],
            0.7 * p[0] - 2.0 * p[2] + 1.0,
        ]
    };
    for (x, dim) in quad_cases(&mut rng) {
        let n = x.len();
        let meas = simplex_measure(&x, dim);
        let mut out = vec![f64::NAN; n * dim];
        cell_load_quadrature(&x, dim, &lin, &mut out);
        // The field at the vertices (z = 0 in 2D).
        let fv: Vec<[f64; 3]> = x
            .iter()
            .map(|p| lin([p[0], p[1], if dim == 2 { 0.0 } else { p[2] }]))
            .collect();
        for a in 0..n {
            for i in 0..dim {
                let expected: f64 = (0..n).map(|b| fv[b][i] * meas * mass_factor(n, a, b)).sum();
                assert!(
                    close(out[a * dim + i], expected, 1e-13),
                    "n={n} dim={dim} a={a} i={i}: {} vs {expected}",
                    out[a * dim + i]
                );
            }
        }
        // A constant field reproduces the lumped loads.
        let c = [0.4, -1.1, 2.0];
        cell_load_quadrature(&x, dim, &|_| c, &mut out);
        let mut lumped = vec![0.0; n * dim];
        if n == dim {
            lumped_facet_load(meas, c, dim, &mut lumped);
        } else if n == dim + 1 {
            body_force_load(meas, c, dim, &mut lumped);
        } else {
            continue; // a segment in 3D is neither facet nor cell
        }
        for i in 0..n * dim {
            assert!(close(out[i], lumped[i], 1e-14));
        }
    }
}

#[test]
fn quadrature_total_exact_for_quadratics() {
    let mut rng = StdRng::seed_from_u64(29);
    // q = l1 * l2 with linear l1, l2: ∫ q = Σ_ab l1(x_a) l2(x_b) |T| (1 + δ_ab) n!/(n+2)!.
    let l1 = |p: [f64; 3]| 0.5 + p[0] - 2.0 * p[1] + 0.3 * p[2];
    let l2 = |p: [f64; 3]| -1.0 + 3.0 * p[0] + p[1] - p[2];
    let l3 = |p: [f64; 3]| 2.0 - p[0] + 0.5 * p[2];
    let f = |p: [f64; 3]| [l1(p) * l2(p), l2(p) * l2(p), l1(p) * l3(p)];
    for (x, dim) in quad_cases(&mut rng) {
        let n = x.len();
        let meas = simplex_measure(&x, dim);
        let xs: Vec<[f64; 3]> = x
            .iter()
            .map(|p| [p[0], p[1], if dim == 2 { 0.0 } else { p[2] }])
            .collect();
        let int = |fa: &dyn Fn([f64; 3]) -> f64, fb: &dyn Fn([f64; 3]) -> f64| -> f64 {
            let mut s = 0.0;
            for a in 0..n {
                for b in 0..n {
                    s += fa(xs[a]) * fb(xs[b]) * meas * mass_factor(n, a, b);
                }
            }
            s
        };
        let exact = [int(&l1, &l2), int(&l2, &l2), int(&l1, &l3)];
        let mut out = vec![0.0; n * dim];
        cell_load_quadrature(&x, dim, &f, &mut out);
        for i in 0..dim {
            let total: f64 = (0..n).map(|a| out[a * dim + i]).sum();
            assert!(
                close(total, exact[i], 1e-13),
                "n={n} dim={dim} i={i}: {total} vs {}",
                exact[i]
            );
        }
    }
}

#[test]
fn simplex_measures() {
    assert!(close(
        simplex_measure(&[[0.0, 0.0, 1.0], [3.0, 4.0, -1.0]], 2),
        5.0,
        1e-15
    ));
    assert!(close(
        simplex_measure(&[[0.0, 0.0, 0.0], [1.0, 2.0, 2.0]], 3),
        3.0,
        1e-15
    ));
    let tri = [[0.0, 0.0, 0.0], [0.0, 2.0, 0.0], [3.0, 0.0, 0.0]];
    assert!(close(simplex_measure(&tri, 2), 3.0, 1e-15));
    let tet = [
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 6.0],
    ];
    assert!(close(simplex_measure(&tet, 3), 1.0, 1e-15));
}

// ---------------------------------------------------------------- throughput

/// Element-kernel throughput (best of 5 rounds, the machine is shared). Run with
/// `cargo test --release --lib fem::tests::kernel_throughput -- --ignored --nocapture`.
#[test]
#[ignore]
fn kernel_throughput() {
    use std::hint::black_box;
    use std::time::Instant;
    let mut rng = StdRng::seed_from_u64(1);
    let tris: Vec<[[f64; 2]; 3]> = (0..1024).map(|_| random_tri(&mut rng)).collect();
    let tets: Vec<[[f64; 3]; 4]> = (0..1024).map(|_| random_tet(&mut rng)).collect();
    let reps = 500;
    let mut best = [f64::INFINITY; 2];
    let mut acc = 0.0;
    for _ in 0..5 {
        let mut k = [0.0; 36];
        let t0 = Instant::now();
        for _ in 0..reps {
            for x in &tris {
                acc += tri_stiffness(black_box(x), 1.2, 0.8, &mut k);
                acc += black_box(&k)[7];
            }
        }
        best[0] = best[0].min(t0.elapsed().as_secs_f64());
        let mut k = [0.0; 144];
        let t0 = Instant::now();
        for _ in 0..reps {
            for x in &tets {
                acc += tet_stiffness(black_box(x), 1.2, 0.8, &mut k);
                acc += black_box(&k)[13];
            }
        }
        best[1] = best[1].min(t0.elapsed().as_secs_f64());
    }
    let n = (reps * 1024) as f64;
    for (name, dt) in [("tri_stiffness", best[0]), ("tet_stiffness", best[1])] {
        println!(
            "{name}: {:.3e} elements/s ({:.1} ns/element)",
            n / dt,
            1e9 * dt / n
        );
    }
    assert!(acc.is_finite());
}
