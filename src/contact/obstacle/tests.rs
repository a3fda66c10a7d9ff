//! Unit tests of the obstacle shapes: projections against brute force and known values, and
//! the rejection of invalid data.

use super::vec3::{add, axpy, norm, scale};
use super::*;
use crate::geom::{dot, sub};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::path::Path;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let d = sub(*a, *b);
    dot(d, d).sqrt()
}

/// The thesis' benchmark: plane y = -1 below the unit disk, n = (0, 1).
#[test]
fn hertz_plane_2d() {
    let p = Plane::new([0.0, -1.0, 0.0], [0.0, 3.0, 0.0], 2).unwrap();
    assert_eq!(p.normal(), [0.0, 1.0, 0.0]);
    // Lowest point of the unit disk touches: gap 0.
    let q = p.project([0.0, -1.0, 0.0]);
    assert_eq!(q.gap, 0.0);
    // A point of the circle at angle 5π/4: gap = 1 − sin(π/4).
    let a = 5.0 * std::f64::consts::PI / 4.0;
    let q = p.project([a.cos(), a.sin(), 0.0]);
    assert!(close(q.gap, 1.0 - (0.5f64).sqrt(), 1e-15));
    assert!(close(q.closest[0], a.cos(), 1e-15) && close(q.closest[1], -1.0, 1e-15));
    // z of the query is ignored in 2D.
    let q2 = p.project([a.cos(), a.sin(), 7.0]);
    assert_eq!(q, q2);
    // Below the plane: negative gap.
    assert!(close(p.project([0.3, -1.5, 0.0]).gap, -0.5, 1e-15));
}

#[test]
fn plane_random_3d() {
    let mut rng = StdRng::seed_from_u64(1);
    for _ in 0..200 {
        let pt = [0.0; 3].map(|_: f64| rng.gen_range(-2.0..2.0));
        let nr = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
        if dot(nr, nr) < 1e-4 {
            continue;
        }
        let p = Plane::new(pt, nr, 3).unwrap();
        let n = p.normal();
        assert!(close(dot(n, n), 1.0, 1e-14));
        assert!(dot(n, nr) > 0.0, "orientation kept");
        let x = [0.0; 3].map(|_: f64| rng.gen_range(-3.0..3.0));
        let q = p.project(x);
        // closest point lies on the plane
        assert!(dot(sub(q.closest, pt), n).abs() < 1e-13);
        // x = closest + g n
        for i in 0..3 {
            assert!(close(x[i], q.closest[i] + q.gap * n[i], 1e-13));
        }
        // |g| is the distance to the plane, and no other point of the plane is closer
        assert!(close(q.gap.abs(), dist(&x, &q.closest), 1e-13));
        let other = [
            q.closest[0] + 0.1 * n[1],
            q.closest[1] - 0.1 * n[0],
            q.closest[2],
        ];
        assert!(dist(&x, &other) >= q.gap.abs() - 1e-13);
        // sign: moving along +n increases the gap by the step
        let x2 = [x[0] + 0.5 * n[0], x[1] + 0.5 * n[1], x[2] + 0.5 * n[2]];
        assert!(close(p.project(x2).gap, q.gap + 0.5, 1e-13));
    }
}

#[test]
fn sphere_2d_and_3d() {
    // 2D disk of radius 2 at (1, 1): point (4, 5) is at distance 5, gap 3, n = (0.6, 0.8).
    let s = Sphere::new([1.0, 1.0, 0.0], 2.0, 2).unwrap();
    let q = s.project([4.0, 5.0, 0.0]).unwrap();
    assert!(close(q.gap, 3.0, 1e-15));
    assert!(close(q.normal[0], 0.6, 1e-15) && close(q.normal[1], 0.8, 1e-15));
    assert_eq!(q.normal[2], 0.0);
    assert!(close(q.closest[0], 2.2, 1e-15) && close(q.closest[1], 2.6, 1e-15));
    // inside: negative gap, normal still from centre to x
    let q = s.project([1.0, 0.0, 0.0]).unwrap();
    assert!(close(q.gap, -1.0, 1e-15));
    assert_eq!(q.normal, [0.0, -1.0, 0.0]);
    assert_eq!(s.project([1.0, 1.0, 0.0]), Err(ObstacleError::AtCentre));

    let mut rng = StdRng::seed_from_u64(2);
    for _ in 0..200 {
        let c = [0.0; 3].map(|_: f64| rng.gen_range(-2.0..2.0));
        let r = rng.gen_range(0.1..3.0);
        let s = Sphere::new(c, r, 3).unwrap();
        let x = [0.0; 3].map(|_: f64| rng.gen_range(-5.0..5.0));
        let q = s.project(x).unwrap();
        assert!(close(dot(q.normal, q.normal), 1.0, 1e-14));
        assert!(close(dist(&q.closest, &c), r, 1e-13));
        assert!(close(q.gap, dist(&x, &c) - r, 1e-13));
        // x = closest + g n; n points from centre to x
        for ((xi, pi), ni) in x.iter().zip(&q.closest).zip(&q.normal) {
            assert!(close(*xi, pi + q.gap * ni, 1e-12));
        }
        assert!(dot(q.normal, sub(x, c)) > 0.0);
        // the closest point really is closest among sampled sphere points
        for _ in 0..5 {
            let d = [0.0; 3].map(|_: f64| rng.gen_range(-1.0..1.0));
            let l = dot(d, d).sqrt();
            if l < 1e-3 {
                continue;
            }
            let y = [
                c[0] + r * d[0] / l,
                c[1] + r * d[1] / l,
                c[2] + r * d[2] / l,
            ];
            assert!(dist(&x, &y) >= q.gap.abs() - 1e-12);
        }
    }
}

#[test]
fn invalid_data() {
    assert_eq!(
        Plane::new([0.0; 3], [0.0; 3], 3),
        Err(ObstacleError::ZeroNormal)
    );
    assert_eq!(
        Plane::new([0.0; 3], [0.0, 1.0, 0.5], 2),
        Err(ObstacleError::NonZeroZ)
    );
    assert_eq!(
        Plane::new([0.0, f64::NAN, 0.0], [0.0, 1.0, 0.0], 2),
        Err(ObstacleError::NotFinite)
    );
    assert_eq!(
        Sphere::new([0.0; 3], 0.0, 3),
        Err(ObstacleError::NonPositiveRadius)
    );
    assert_eq!(
        Sphere::new([0.0; 3], -1.0, 3),
        Err(ObstacleError::NonPositiveRadius)
    );
    assert_eq!(
        Sphere::new([0.0, 0.0, 1.0], 1.0, 2),
        Err(ObstacleError::NonZeroZ)
    );
    assert_eq!(Sphere::new([0.0; 3], 1.0, 4), Err(ObstacleError::BadDim(4)));
    let e = ObstacleError::AtCentre.into_input_error(Path::new("case.toml"), "obstacle");
    assert_eq!(e.key.as_deref(), Some("obstacle"));
    assert!(e.to_string().starts_with("case.toml: key 'obstacle': "));
    let o = Obstacle::Sphere(Sphere::new([0.0; 3], 1.0, 3).unwrap());
    assert_eq!(o.project([0.0; 3]), Err(ObstacleError::AtCentre));
    assert_eq!(o.dim(), 3);
}

// ---- the indenter shapes -------------------------------------------------------------

fn rand_vec(rng: &mut StdRng, lo: f64, hi: f64, dim: usize) -> [f64; 3] {
    let mut v = [0.0; 3].map(|_: f64| rng.gen_range(lo..hi));
    if dim == 2 {
        v[2] = 0.0;
    }
    v
}

fn rand_unit(rng: &mut StdRng, dim: usize) -> [f64; 3] {
    loop {
        let v = rand_vec(rng, -1.0, 1.0, dim);
        let l = dot(v, v).sqrt();
        if l > 0.2 {
            return v.map(|x| x / l);
        }
    }
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Rodrigues: v rotated by the angle φ about the unit axis k.
fn rotate(v: [f64; 3], k: [f64; 3], phi: f64) -> [f64; 3] {
    let (s, c) = phi.sin_cos();
    let kv = cross3(k, v);
    let kd = dot(k, v);
    [0, 1, 2].map(|i| v[i] * c + kv[i] * s + k[i] * kd * (1.0 - c))
}

/// Unit normal, x = closest + g n, and the finite-difference gradient of the gap equal to
/// n (central differences with step h; `smooth` false skips the gradient check).
fn check_common(o: &Obstacle, x: [f64; 3], q: &Projection, smooth: bool, what: &str) {
    let dim = o.dim();
    let n = q.normal;
    assert!(close(dot(n, n), 1.0, 1e-13), "{what}: |n| at {x:?}: {n:?}");
    for i in 0..dim {
        assert!(
            close(x[i], q.closest[i] + q.gap * n[i], 1e-12),
            "{what}: x = closest + g n at {x:?}: {q:?}"
        );
    }
    if dim == 2 {
        assert_eq!((n[2], q.closest[2]), (0.0, 0.0), "{what}");
    }
    if smooth {
        let h = 1e-7;
        for i in 0..dim {
            let (mut xp, mut xm) = (x, x);
            xp[i] += h;
            xm[i] -= h;
            let g = (o.project(xp).unwrap().gap - o.project(xm).unwrap().gap) / (2.0 * h);
            assert!(
                close(g, n[i], 1e-6),
                "{what}: d gap / dx_{i} = {g} but n = {n:?} at {x:?}"
            );
        }
    }
}

#[test]
fn reference_direction_is_unit_and_perpendicular() {
    assert_eq!(reference_direction([0.0, 0.0, 1.0]), [1.0, 0.0, 0.0]);
    assert_eq!(reference_direction([0.0, 0.0, -1.0]), [1.0, 0.0, 0.0]);
    assert_eq!(reference_direction([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]);
    assert_eq!(reference_direction([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]);
    let mut rng = StdRng::seed_from_u64(10);
    for dim in [2, 3] {
        for _ in 0..200 {
            let a = rand_unit(&mut rng, dim);
            let r = reference_direction(a);
            assert!(close(dot(r, r), 1.0, 1e-14) && dot(r, a).abs() < 1e-14);
            if dim == 2 {
                assert_eq!(r[2], 0.0);
            }
        }
    }
}

#[test]
fn cylinder_random_points() {
    let mut rng = StdRng::seed_from_u64(11);
    for _ in 0..300 {
        let p = rand_vec(&mut rng, -2.0, 2.0, 3);
        let a = rand_unit(&mut rng, 3);
        let r = rng.gen_range(0.1..2.0);
        let c = Cylinder::new(p, a.map(|x| 3.0 * x), r, 3).unwrap();
        assert!(close(dot(c.axis(), a), 1.0, 1e-14));
        let o = Obstacle::Cylinder(c);
        // Points both sides, some close to the surface.
        let x = if rng.gen_bool(0.5) {
            rand_vec(&mut rng, -4.0, 4.0, 3)
        } else {
            let y = add(p, scale(rng.gen_range(-3.0..3.0), a));
            let w = cross3(a, rand_unit(&mut rng, 3));
            let w = scale(1.0 / norm(w), w);
            axpy(y, r + rng.gen_range(-1e-3..1e-3), w)
        };
        let q = o.project(x).unwrap();
        // Independent: the distance to the axis line is |(x − p) × a|.
        let rho = norm(cross3(sub(x, p), a));
        assert!(close(q.gap, rho - r, 1e-12), "{} vs {}", q.gap, rho - r);
        assert!(dot(q.normal, a).abs() < 1e-12);
        assert!(close(norm(cross3(sub(q.closest, p), a)), r, 1e-12));
        check_common(&o, x, &q, rho > 1e-3, "cylinder");
    }
    let c = Cylinder::new([0.0; 3], [0.0, 0.0, 1.0], 1.0, 3).unwrap();
    assert_eq!(c.project([0.0, 0.0, 5.0]), Err(ObstacleError::OnAxis));
    let q = c.project([0.0, 2.0, 7.0]).unwrap();
    assert_eq!(
        (q.gap, q.normal, q.closest),
        (1.0, [0.0, 1.0, 0.0], [0.0, 1.0, 7.0])
    );
}

/// Independent signed distance of the cone through the angle θ between x − apex and the
/// axis: inside (θ ≤ α) −|d| sin(α − θ); outside |d| sin(θ − α) while θ − α ≤ 90°,
/// else |d| (the apex).
fn cone_gap_by_angle(apex: [f64; 3], a: [f64; 3], alpha: f64, x: [f64; 3]) -> f64 {
    let d = sub(x, apex);
    let len = norm(d);
    let theta = norm(cross3(d, a)).atan2(dot(d, a));
    if theta <= alpha {
        -len * (alpha - theta).sin()
    } else if theta - alpha <= std::f64::consts::FRAC_PI_2 {
        len * (theta - alpha).sin()
    } else {
        len
    }
}

#[test]
fn cone_random_points_2d_and_3d() {
    let mut rng = StdRng::seed_from_u64(12);
    for dim in [2, 3] {
        for _ in 0..400 {
            let apex = rand_vec(&mut rng, -1.0, 1.0, dim);
            let a = rand_unit(&mut rng, dim);
            let deg = rng.gen_range(5.0..85.0);
            let alpha = f64::to_radians(deg);
            let c = Cone::new(apex, a.map(|x| 0.5 * x), deg, dim).unwrap();
            let o = Obstacle::Cone(c);
            assert_eq!(o.dim(), dim);
            let x = match rng.gen_range(0..3) {
                0 => rand_vec(&mut rng, -3.0, 3.0, dim),
                // near the apex
                1 => axpy(apex, 1e-3, rand_vec(&mut rng, -1.0, 1.0, dim)),
                // near the surface: a generator point moved off it by ±1e-4
                _ => {
                    let w = cross3(a, rand_unit(&mut rng, dim));
                    let w = if dim == 2 {
                        [-a[1], a[0], 0.0]
                    } else {
                        scale(1.0 / norm(w), w)
                    };
                    let gen = add(scale(alpha.cos(), a), scale(alpha.sin(), w));
                    let y = axpy(apex, rng.gen_range(0.0..2.0), gen);
                    axpy(y, 1e-4, rand_vec(&mut rng, -1.0, 1.0, dim))
                }
            };
            let q = o.project(x).unwrap();
            let want = cone_gap_by_angle(apex, a, alpha, x);
            assert!(close(q.gap, want, 1e-12), "{dim}D: {} vs {want}", q.gap);
            // The closest point lies on the surface: the apex or at the angle α.
            let y = sub(q.closest, apex);
            if norm(y) > 1e-9 {
                let th = norm(cross3(y, a)).atan2(dot(y, a));
                assert!(close(th, alpha, 1e-9), "{th} vs {alpha}");
            }
            // Smooth away from the axis and the apex.
            let d = sub(x, apex);
            let smooth = norm(d) > 1e-3 && norm(cross3(d, a)) > 1e-3;
            check_common(&o, x, &q, smooth, "cone");
        }
    }
}

#[test]
fn cone_apex_axis_and_known_values() {
    // 2D wedge, tip at the origin, axis +y, half angle 45°.
    let c = Cone::new([0.0; 3], [0.0, 2.0, 0.0], 45.0, 2).unwrap();
    let s = 0.5f64.sqrt();
    // At the apex: g = 0, n = −axis.
    let q = c.project([0.0, 0.0, 3.0]).unwrap();
    assert_eq!(
        (q.gap, q.normal, q.closest),
        (0.0, [0.0, -1.0, 0.0], [0.0; 3])
    );
    // Below the tip on the axis: the apex is nearest, n = −axis.
    let q = c.project([0.0, -2.0, 0.0]).unwrap();
    assert_eq!((q.gap, q.normal), (2.0, [0.0, -1.0, 0.0]));
    // Beside the wedge: the face x = y is nearest.
    let q = c.project([1.0, 0.0, 0.0]).unwrap();
    assert!(close(q.gap, s, 1e-15) && close(q.normal[0], s, 1e-15));
    assert!(close(q.normal[1], -s, 1e-15));
    assert!(close(q.closest[0], 0.5, 1e-15) && close(q.closest[1], 0.5, 1e-15));
    // Inside on the axis: both faces are nearest, the one towards r0 = +x is taken.
    let q = c.project([0.0, 1.0, 0.0]).unwrap();
    assert!(close(q.gap, -s, 1e-15));
    assert!(close(q.normal[0], s, 1e-15) && close(q.normal[1], -s, 1e-15));
    // 3D, axis +z: inside on the axis also takes r0 = x.
    let c = Cone::new([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 60.0, 3).unwrap();
    let q = c.project([0.0, 0.0, 3.0]).unwrap();
    let (sa, ca) = 60f64.to_radians().sin_cos();
    assert!(close(q.gap, -2.0 * sa, 1e-15));
    assert!(close(q.normal[0], ca, 1e-15) && close(q.normal[2], -sa, 1e-15));
    assert_eq!(q.normal[1], 0.0);
}

#[test]
fn pyramid_face_conventions() {
    // Vickers: 4 faces at 68°, axis +z, azimuth 0: faces towards +x, +y, −x, −y.
    let b = 68f64.to_radians();
    let p = Pyramid::new([0.0; 3], [0.0, 0.0, 1.0], 68.0, 4, 0.0, 3).unwrap();
    let want = [
        [b.cos(), 0.0, -b.sin()],
        [0.0, b.cos(), -b.sin()],
        [-b.cos(), 0.0, -b.sin()],
        [0.0, -b.cos(), -b.sin()],
    ];
    for (k, w) in want.iter().enumerate() {
        let m = p.face_normal(k);
        for i in 0..3 {
            assert!(close(m[i], w[i], 1e-15), "face {k}: {m:?}");
        }
    }
    // Its edges lie on the diagonals; the face-to-axis angle is 68°.
    let e = p.edge(0);
    assert!(close(e[0], e[1], 1e-15) && e[0] > 0.0 && e[2] > 0.0);
    // A point above face 0 (off its centre line) projects onto face 0 along m_0.
    let x = [1.0, 0.1, 0.2];
    let q = p.project(x).unwrap();
    assert!(close(q.gap, dot(x, want[0]), 1e-15) && q.normal == p.face_normal(0));
    // Berkovich, azimuth 90°: face 0 faces +y, the others at 210° and 330°.
    let b = 65.27f64.to_radians();
    let p = Pyramid::new([0.0; 3], [0.0, 0.0, 1.0], 65.27, 3, 90.0, 3).unwrap();
    for (k, phi) in [90.0f64, 210.0, 330.0].iter().enumerate() {
        let m = p.face_normal(k);
        let (s, c) = phi.to_radians().sin_cos();
        let w = [b.cos() * c, b.cos() * s, -b.sin()];
        for i in 0..3 {
            assert!(close(m[i], w[i], 1e-15), "face {k}: {m:?} vs {w:?}");
        }
    }
    // At the apex: n = −axis; straight below it, too.
    let q = p.project([0.0; 3]).unwrap();
    assert_eq!((q.gap, q.normal), (0.0, [0.0, 0.0, -1.0]));
    let q = p.project([0.0, 0.0, -0.5]).unwrap();
    assert_eq!(
        (q.gap, q.normal, q.closest),
        (0.5, [0.0, 0.0, -1.0], [0.0; 3])
    );
    // Inside on the axis: the first face is taken.
    let q = p.project([0.0, 0.0, 1.0]).unwrap();
    assert!(close(q.gap, -b.sin(), 1e-15) && q.normal == p.face_normal(0));
}

#[test]
fn pyramid_random_points() {
    let mut rng = StdRng::seed_from_u64(13);
    for _ in 0..400 {
        let apex = rand_vec(&mut rng, -1.0, 1.0, 3);
        let a = rand_unit(&mut rng, 3);
        let deg = rng.gen_range(10.0..85.0);
        let nf = rng.gen_range(3..9);
        let az = rng.gen_range(-400.0..400.0);
        let p = Pyramid::new(apex, a.map(|x| 2.0 * x), deg, nf, az, 3).unwrap();
        let o = Obstacle::Pyramid(p);
        // Independent face normals: m_0 rotated about the axis by 360° k / N.
        let m0 = p.face_normal(0);
        assert!(close(dot(m0, a), -f64::to_radians(deg).sin(), 1e-14));
        let ms: Vec<[f64; 3]> = (0..nf)
            .map(|k| rotate(m0, a, std::f64::consts::TAU * k as f64 / nf as f64))
            .collect();
        for (k, m) in ms.iter().enumerate() {
            let mk = p.face_normal(k);
            assert!((0..3).all(|i| close(mk[i], m[i], 1e-13)), "face {k}");
        }
        // Independent edges: m_k × m_{k+1}, oriented into the indenter.
        let es: Vec<[f64; 3]> = (0..nf)
            .map(|k| {
                let e = cross3(ms[k], ms[(k + 1) % nf]);
                let e = scale(1.0 / norm(e), e);
                if dot(e, a) < 0.0 {
                    scale(-1.0, e)
                } else {
                    e
                }
            })
            .collect();
        for (k, e) in es.iter().enumerate() {
            let ek = p.edge(k);
            assert!((0..3).all(|i| close(ek[i], e[i], 1e-13)), "edge {k}");
        }
        let x = match rng.gen_range(0..3) {
            0 => rand_vec(&mut rng, -3.0, 3.0, 3),
            1 => axpy(apex, 1e-3, rand_vec(&mut rng, -1.0, 1.0, 3)),
            // near an edge
            _ => {
                let y = axpy(apex, rng.gen_range(0.0..2.0), es[rng.gen_range(0..nf)]);
                axpy(y, 1e-4, rand_vec(&mut rng, -1.0, 1.0, 3))
            }
        };
        let q = o.project(x).unwrap();
        let d = sub(x, apex);
        let y = sub(q.closest, apex);
        let smax = ms.iter().map(|m| dot(d, *m)).fold(f64::MIN, f64::max);
        // The closest point is on the surface.
        let ymax = ms.iter().map(|m| dot(y, *m)).fold(f64::MIN, f64::max);
        assert!(ymax.abs() < 1e-12, "{ymax}");
        let smooth = if smax <= 0.0 {
            // Inside: the distance to the nearest face plane.
            assert!(close(q.gap, smax, 1e-13), "{} vs {smax}", q.gap);
            let mut s: Vec<f64> = ms.iter().map(|m| dot(d, *m)).collect();
            s.sort_by(|u, v| v.total_cmp(u));
            s[0] - s[1] > 1e-4
        } else {
            // Outside: y is the projection onto the convex cone K (Moreau): y ∈ K,
            // (d − y)·y = 0 and d − y in the polar cone, i.e. (d − y)·e_k ≤ 0 for the
            // generators e_k of K.
            let w = sub(d, y);
            assert!(close(q.gap, norm(w), 1e-12) && q.gap > 0.0);
            assert!(dot(w, y).abs() < 1e-12, "{}", dot(w, y));
            for e in &es {
                assert!(dot(w, *e) < 1e-12, "{}", dot(w, *e));
            }
            // The distance to a convex set is smooth outside it (its Hessian ~ 1/gap).
            q.gap > 1e-3
        };
        check_common(&o, x, &q, smooth, "pyramid");
    }
}

/// Independent signed distance of the punch from its meridian profile: the flat segment
/// t = 0, ρ ≤ R − r_e, the quarter arc of radius r_e about (r_e, R − r_e) and the side
/// ρ = R, t ≥ r_e; negative inside.
fn punch_gap_by_profile(t: f64, rho: f64, r: f64, h: f64) -> f64 {
    let rp = r - h;
    let seg = |p: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let l2 = dx * dx + dy * dy;
        let s = if l2 > 0.0 {
            (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p.0 - a.0 - s * dx).hypot(p.1 - a.1 - s * dy)
    };
    let flat = seg((t, rho), (0.0, 0.0), (0.0, rp));
    let side = if t >= h {
        (rho - r).abs()
    } else {
        (t - h).hypot(rho - r)
    };
    let arc = if t <= h && rho >= rp {
        ((t - h).hypot(rho - rp) - h).abs()
    } else {
        t.hypot(rho - rp).min((t - h).hypot(rho - r))
    };
    let dist = flat.min(side).min(arc);
    let inside = t >= 0.0 && rho <= r && !(t < h && rho > rp && (t - h).hypot(rho - rp) > h);
    if inside {
        -dist
    } else {
        dist
    }
}

#[test]
fn punch_random_points_2d_and_3d() {
    let mut rng = StdRng::seed_from_u64(14);
    for dim in [2, 3] {
        for case in 0..450 {
            let c0 = rand_vec(&mut rng, -1.0, 1.0, dim);
            let a = rand_unit(&mut rng, dim);
            let r = rng.gen_range(0.2..2.0);
            // sharp, round-nosed and in between
            let h = match case % 3 {
                0 => 0.0,
                1 => r,
                _ => rng.gen_range(0.0..r),
            };
            let p = Punch::new(c0, a.map(|x| 4.0 * x), r, h, dim).unwrap();
            let o = Obstacle::Punch(p);
            assert_eq!(o.dim(), dim);
            let x = match rng.gen_range(0..3) {
                0 => axpy(c0, 1.5 * r, rand_vec(&mut rng, -1.0, 1.0, dim)),
                // near the edge
                1 => {
                    let w = if dim == 2 {
                        [-a[1], a[0], 0.0]
                    } else {
                        let w = cross3(a, rand_unit(&mut rng, 3));
                        scale(1.0 / norm(w), w)
                    };
                    let y = add(c0, scale(r, w));
                    axpy(y, 1e-3 * r + h, rand_vec(&mut rng, -1.0, 1.0, dim))
                }
                // near the face centre, and on the axis
                _ => axpy(c0, rng.gen_range(-0.5..1.5) * r, a),
            };
            let q = o.project(x).unwrap();
            let d = sub(x, c0);
            let t = dot(d, a);
            let rho = norm(cross3(d, a));
            let want = punch_gap_by_profile(t, rho, r, h);
            assert!(
                close(q.gap, want, 1e-12),
                "{dim}D R {r} r_e {h}: {} vs {want} at t {t} rho {rho}",
                q.gap
            );
            // Smooth away from the axis (ρ = 0 is a symmetry line), the sharp corner, the
            // face-side ties inside (t − r_e = R − r_e − ρ) and their extension.
            let (u, v) = (h - t, rho - (r - h));
            let smooth = rho > 1e-3
                && (u.abs() > 1e-3 || v.abs() > 1e-3)
                && !(u <= 1e-3 && v <= 1e-3 && (u - v).abs() < 1e-3);
            check_common(&o, x, &q, smooth, "punch");
        }
    }
}

#[test]
fn punch_known_values() {
    // 3D punch, face centred at the origin, axis +z, R = 1, r_e = 0.2.
    let p = Punch::new([0.0; 3], [0.0, 0.0, 1.0], 1.0, 0.2, 3).unwrap();
    // Below the face: the flat face is nearest, n = −axis.
    let q = p.project([0.3, 0.0, -0.5]).unwrap();
    assert_eq!((q.gap, q.normal), (0.5, [0.0, 0.0, -1.0]));
    assert!(close(q.closest[0], 0.3, 1e-15) && q.closest[2] == 0.0);
    // Beside the side: n radial.
    let q = p.project([0.0, 1.5, 2.0]).unwrap();
    assert_eq!((q.gap, q.normal), (0.5, [0.0, 1.0, 0.0]));
    // Diagonally off the rounded edge: centre of the edge circle (t, ρ) = (0.2, 0.8).
    let q = p.project([1.1, 0.0, -0.2]).unwrap();
    assert!(close(q.gap, 0.5 - 0.2, 1e-15), "{}", q.gap);
    assert!(close(q.normal[0], 0.6, 1e-15) && close(q.normal[2], -0.8, 1e-15));
    // Inside, nearer the face than the side: depth along −axis; a tie goes to the face.
    let q = p.project([0.0, 0.0, 0.1]).unwrap();
    assert_eq!((q.gap, q.normal), (-0.1, [0.0, 0.0, -1.0]));
    let q = p.project([0.6, 0.0, 0.4]).unwrap();
    assert!(close(q.gap, -0.4, 1e-15) && q.normal == [0.0, 0.0, -1.0]);
    // Deep inside on the axis: the side towards r0 = +x.
    let q = p.project([0.0, 0.0, 3.0]).unwrap();
    assert_eq!((q.gap, q.normal), (-1.0, [1.0, 0.0, 0.0]));
    // 2D strip, sharp corners: a point off the corner (1, 0) at (2, −1).
    let p = Punch::new([0.0; 3], [0.0, 1.0, 0.0], 1.0, 0.0, 2).unwrap();
    let q = p.project([2.0, -1.0, 5.0]).unwrap();
    let s = 0.5f64.sqrt();
    assert!(close(q.gap, 2f64.sqrt(), 1e-15));
    assert!(close(q.normal[0], s, 1e-15) && close(q.normal[1], -s, 1e-15));
    assert!(close(q.closest[0], 1.0, 1e-15) && close(q.closest[1], 0.0, 1e-15));
}

#[test]
fn invalid_indenter_data() {
    let z = [0.0, 0.0, 1.0];
    assert_eq!(
        Cylinder::new([0.0; 3], [0.0, 1.0, 0.0], 1.0, 2),
        Err(ObstacleError::Only3D("cylinder"))
    );
    assert_eq!(
        Cylinder::new([0.0; 3], [0.0; 3], 1.0, 3),
        Err(ObstacleError::ZeroAxis)
    );
    assert_eq!(
        Cylinder::new([0.0; 3], z, 0.0, 3),
        Err(ObstacleError::BadRadius)
    );
    assert_eq!(
        Cylinder::new([0.0; 3], z, f64::INFINITY, 3),
        Err(ObstacleError::NotFinite)
    );
    for bad in [0.0, 90.0, -5.0, 120.0] {
        assert_eq!(
            Cone::new([0.0; 3], z, bad, 3),
            Err(ObstacleError::BadHalfAngle)
        );
        assert_eq!(
            Pyramid::new([0.0; 3], z, bad, 4, 0.0, 3),
            Err(ObstacleError::BadHalfAngle)
        );
    }
    assert_eq!(
        Cone::new([0.0; 3], [0.0, 1.0, 1.0], 30.0, 2),
        Err(ObstacleError::NonZeroZ)
    );
    assert_eq!(
        Cone::new([0.0; 3], z, f64::NAN, 3),
        Err(ObstacleError::NotFinite)
    );
    assert_eq!(
        Pyramid::new([0.0; 3], [0.0, 1.0, 0.0], 60.0, 4, 0.0, 2),
        Err(ObstacleError::Only3D("pyramid"))
    );
    for n in [0, 2, MAX_FACES + 1] {
        assert_eq!(
            Pyramid::new([0.0; 3], z, 60.0, n, 0.0, 3),
            Err(ObstacleError::BadFaces(n))
        );
    }
    assert!(Pyramid::new([0.0; 3], z, 60.0, MAX_FACES, 0.0, 3).is_ok());
    assert_eq!(
        Pyramid::new([0.0; 3], z, 60.0, 3, f64::INFINITY, 3),
        Err(ObstacleError::NotFinite)
    );
    assert_eq!(
        Punch::new([0.0; 3], z, 1.0, 1.5, 3),
        Err(ObstacleError::BadEdgeRadius)
    );
    assert_eq!(
        Punch::new([0.0; 3], z, 1.0, -0.1, 3),
        Err(ObstacleError::BadEdgeRadius)
    );
    assert_eq!(
        Punch::new([0.0; 3], z, -1.0, 0.0, 3),
        Err(ObstacleError::BadRadius)
    );
    assert!(Punch::new([0.0; 3], z, 1.0, 1.0, 3).is_ok());
    let c = Cone::new([0.0; 3], z, 30.0, 3).unwrap();
    assert_eq!(
        c.project([f64::NAN, 0.0, 0.0]),
        Err(ObstacleError::NotFinite)
    );
    assert!(ObstacleError::Only3D("cylinder")
        .to_string()
        .contains("cylinder"));
    assert!(ObstacleError::BadFaces(2).to_string().contains("got 2"));
}
