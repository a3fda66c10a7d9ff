//! The `surface` obstacle (3D only): the solid inside a closed triangulated surface read from
//! an STL file, ASCII or binary (docs/obstacles.md, "surface").
//!
//! The triangles are checked when the file is read ([`TriSurface::from_triangles`]): finite
//! coordinates, no degenerate triangle, a closed surface (every edge shared by exactly two
//! triangles, vertices joined by identical coordinates), consistently oriented, enclosing a
//! positive volume (normals outward). The nearest point and the side come from `parry3d-f64`'s
//! triangle mesh: a bounding-volume hierarchy for the nearest triangle, angle-weighted
//! pseudo-normals for inside/outside.

use super::obstacle::Projection;
use parry3d_f64::math::Vector;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};
use std::collections::HashMap;
use std::fmt;
use std::path::Path;

/// A closed, outward-oriented triangle surface with its BVH.
pub struct TriSurface {
    mesh: TriMesh,
    /// The length of the diagonal of the bounding box.
    size: f64,
    /// The enclosed volume (> 0).
    volume: f64,
}

impl fmt::Debug for TriSurface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "TriSurface({} vertices, {} triangles, volume {})",
            self.mesh.vertices().len(),
            self.mesh.num_triangles(),
            self.volume
        )
    }
}

impl PartialEq for TriSurface {
    fn eq(&self, other: &Self) -> bool {
        self.mesh.indices() == other.mesh.indices() && self.mesh.vertices() == other.mesh.vertices()
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A point in messages.
fn pt(p: [f64; 3]) -> String {
    format!("({}, {}, {})", p[0], p[1], p[2])
}

/// Vertices joined by identical coordinates (as STL writers repeat them), and the triangles
/// as index triples.
fn index_triangles(tris: &[[[f64; 3]; 3]]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut ids: HashMap<[u64; 3], u32> = HashMap::new();
    let mut verts: Vec<[f64; 3]> = Vec::new();
    let mut idx = Vec::with_capacity(tris.len());
    for t in tris {
        let mut tri = [0u32; 3];
        for (k, p) in t.iter().enumerate() {
            // +0.0 joins −0.0 and 0.0.
            let key = p.map(|v| (v + 0.0).to_bits());
            tri[k] = *ids.entry(key).or_insert_with(|| {
                verts.push(*p);
                (verts.len() - 1) as u32
            });
        }
        idx.push(tri);
    }
    (verts, idx)
}

/// Every undirected edge used by exactly two triangles, once in each direction.
fn check_closed(verts: &[[f64; 3]], idx: &[[u32; 3]]) -> Result<(), String> {
    // (min, max) → (triangles using it, in the direction min → max, against it).
    let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::new();
    for (t, tri) in idx.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((t, a < b));
        }
    }
    let mut keys: Vec<_> = edges.keys().copied().collect();
    keys.sort_unstable();
    for key in keys {
        let uses = &edges[&key];
        let (p, q) = (pt(verts[key.0 as usize]), pt(verts[key.1 as usize]));
        let list = uses
            .iter()
            .map(|(t, _)| (t + 1).to_string())
            .collect::<Vec<_>>()
            .join(", ");
        if uses.len() == 1 {
            return Err(format!(
                "the surface is not closed: the edge {p}–{q} belongs to triangle {list} only \
                 (every edge must be shared by exactly two triangles, their common vertices \
                 written with identical coordinates)"
            ));
        }
        if uses.len() > 2 {
            return Err(format!(
                "the surface is not a closed manifold: the edge {p}–{q} is shared by {} \
                 triangles ({list}); every edge must be shared by exactly two",
                uses.len()
            ));
        }
        if uses[0].1 == uses[1].1 {
            return Err(format!(
                "triangles {} and {} are oriented inconsistently: they run through their common \
                 edge {p}–{q} in the same direction (the vertices of every triangle must be \
                 ordered counter-clockwise seen from outside)",
                uses[0].0 + 1,
                uses[1].0 + 1
            ));
        }
    }
    Ok(())
}

impl TriSurface {
    /// The surface of `tris` (each three vertices; the outward normal by the right-hand rule),
    /// checked (see the module doc). The error is a sentence for the user (triangles counted
    /// from 1).
    pub fn from_triangles(tris: &[[[f64; 3]; 3]]) -> Result<Self, String> {
        if tris.is_empty() {
            return Err("the file holds no triangles".into());
        }
        if let Some(t) = tris
            .iter()
            .position(|t| t.iter().flatten().any(|v| !v.is_finite()))
        {
            return Err(format!(
                "triangle {} has a coordinate that is not a finite number",
                t + 1
            ));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in tris.iter().flatten() {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let d = sub(hi, lo);
        let size = dot(d, d).sqrt();
        let mut volume = 0.0;
        for (i, [a, b, c]) in tris.iter().enumerate() {
            let area2 = cross(sub(*b, *a), sub(*c, *a));
            // Twice the area against the size²: relative round-off of the cross product.
            if dot(area2, area2).sqrt() <= 1e-12 * size * size {
                return Err(format!(
                    "triangle {} is degenerate (zero area): its vertices are {}, {}, {}",
                    i + 1,
                    pt(*a),
                    pt(*b),
                    pt(*c)
                ));
            }
            volume += dot(*a, cross(*b, *c)) / 6.0;
        }
        let (verts, idx) = index_triangles(tris);
        check_closed(&verts, &idx)?;
        // The volume of a closed surface does not depend on the origin; its round-off does:
        // judged against the size³.
        if volume.abs() <= 1e-12 * size.powi(3) {
            return Err("the surface encloses no volume".into());
        }
        if volume < 0.0 {
            return Err(format!(
                "the surface is inside-out: its triangles are oriented inward (the enclosed \
                 volume comes out negative, {volume:e}); flip the orientation of every triangle \
                 (reverse its vertex order) so that the normals point out of the obstacle"
            ));
        }
        let vertices: Vec<Vector> = verts
            .iter()
            .map(|p| Vector::new(p[0], p[1], p[2]))
            .collect();
        let mesh = TriMesh::with_flags(vertices, idx, TriMeshFlags::ORIENTED)
            .map_err(|e| format!("the triangle mesh could not be built: {e}"))?;
        Ok(TriSurface { mesh, size, volume })
    }

    /// Reads and checks an STL file (ASCII or binary).
    pub fn read_stl(path: &Path) -> Result<Self, String> {
        // a device or a pipe (e.g. /dev/zero) would be read without end
        let meta = std::fs::metadata(path).map_err(|e| format!("cannot read the file: {e}"))?;
        if !meta.is_file() {
            return Err("not a regular file".into());
        }
        let bytes = std::fs::read(path).map_err(|e| format!("cannot read the file: {e}"))?;
        let tris = parse_stl(&bytes)?;
        Self::from_triangles(&tris)
    }

    pub fn num_triangles(&self) -> usize {
        self.mesh.num_triangles()
    }

    /// The enclosed volume.
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// The diagonal of the bounding box.
    pub fn size(&self) -> f64 {
        self.size
    }

    /// Nearest point y of the surface, signed distance g0 (negative inside) and normal n with
    /// x = y + g0 n: outside n points from y to x, inside from x to y (the shortest way out).
    /// A point on the surface (|x − y| ≤ 10⁻¹⁴ × size) gets the outward normal of the
    /// triangle its nearest point was found on.
    pub fn project(&self, x: [f64; 3]) -> Projection {
        let p = Vector::new(x[0], x[1], x[2]);
        let (proj, (tri, _)) = self.mesh.project_local_point_and_get_location(p, false);
        let y = [proj.point.x, proj.point.y, proj.point.z];
        let d = sub(x, y);
        let dist = dot(d, d).sqrt();
        let sign = if proj.is_inside { -1.0 } else { 1.0 };
        if dist <= 1e-14 * self.size {
            let t = self.mesh.triangle(tri);
            let n = cross(
                sub([t.b.x, t.b.y, t.b.z], [t.a.x, t.a.y, t.a.z]),
                sub([t.c.x, t.c.y, t.c.z], [t.a.x, t.a.y, t.a.z]),
            );
            let len = dot(n, n).sqrt();
            let n = n.map(|v| v / len);
            let g = dot(d, n);
            return Projection {
                closest: [x[0] - g * n[0], x[1] - g * n[1], x[2] - g * n[2]],
                normal: n,
                gap: g,
            };
        }
        let n = d.map(|v| sign * v / dist);
        Projection {
            closest: y,
            normal: n,
            gap: sign * dist,
        }
    }
}

/// The triangles of an STL file: binary when its length is 84 + 50 × (the count in bytes
/// 80..84), else ASCII (`solid` … `facet` … `outer loop`, three `vertex x y z`, `endloop`,
/// `endfacet` … `endsolid`; several solids may follow each other).
pub fn parse_stl(bytes: &[u8]) -> Result<Vec<[[f64; 3]; 3]>, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|m| m.checked_add(84)) == Some(bytes.len()) {
            return Ok(parse_binary(&bytes[84..], n));
        }
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        "not a valid STL file: neither binary STL (84 + 50 bytes per triangle) nor ASCII text"
            .to_string()
    })?;
    parse_ascii(text)
}

fn parse_binary(b: &[u8], n: usize) -> Vec<[[f64; 3]; 3]> {
    let f = |o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as f64;
    (0..n)
        .map(|t| {
            // 12 bytes of normal (ignored: the vertex order defines it), 3 vertices, 2 bytes.
            let o = 50 * t + 12;
            let v = |k: usize| [f(o + 12 * k), f(o + 12 * k + 4), f(o + 12 * k + 8)];
            [v(0), v(1), v(2)]
        })
        .collect()
}

fn parse_ascii(text: &str) -> Result<Vec<[[f64; 3]; 3]>, String> {
    let bad = |line: usize, what: &str| format!("not a valid STL file: line {line}: {what}");
    let mut tris = Vec::new();
    let mut loop_: Option<(usize, Vec<[f64; 3]>)> = None;
    let mut solid = false;
    let mut first = true;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut w = raw.split_whitespace();
        let Some(word) = w.next() else { continue };
        if first && word != "solid" {
            return Err(bad(line, "an ASCII STL file starts with 'solid'"));
        }
        first = false;
        match word {
            "solid" if !solid => solid = true,
            "endsolid" if solid && loop_.is_none() => solid = false,
            "facet" | "endfacet" if solid && loop_.is_none() => {}
            "outer" if solid && loop_.is_none() => loop_ = Some((line, Vec::new())),
            "vertex" => {
                let Some((_, vs)) = loop_.as_mut() else {
                    return Err(bad(line, "'vertex' outside 'outer loop' … 'endloop'"));
                };
                let c: Vec<f64> = w.by_ref().take(3).filter_map(|s| s.parse().ok()).collect();
                if c.len() != 3 || w.next().is_some() {
                    return Err(bad(line, "'vertex' needs three numbers"));
                }
                vs.push([c[0], c[1], c[2]]);
            }
            "endloop" => {
                let Some((start, vs)) = loop_.take() else {
                    return Err(bad(line, "'endloop' without 'outer loop'"));
                };
                if vs.len() != 3 {
                    return Err(bad(
                        start,
                        &format!("a facet needs 3 vertices, this one has {}", vs.len()),
                    ));
                }
                tris.push([vs[0], vs[1], vs[2]]);
            }
            _ => return Err(bad(line, &format!("unexpected '{word}'"))),
        }
    }
    if first {
        return Err("not a valid STL file: the file is empty".into());
    }
    if loop_.is_some() || solid {
        return Err("not a valid STL file: it ends inside a 'solid' (no 'endsolid')".into());
    }
    Ok(tris)
}

/// Writes `tris` as an ASCII STL solid named `name` (vertices with 17 significant digits, so
/// that reading them back gives the same f64 values; facet normals from the vertex order).
pub fn write_stl_ascii(
    w: &mut impl std::io::Write,
    name: &str,
    tris: &[[[f64; 3]; 3]],
) -> std::io::Result<()> {
    writeln!(w, "solid {name}")?;
    for [a, b, c] in tris {
        let n = cross(sub(*b, *a), sub(*c, *a));
        let len = dot(n, n).sqrt();
        let n = n.map(|v| if len > 0.0 { v / len } else { 0.0 });
        writeln!(w, "  facet normal {:e} {:e} {:e}", n[0], n[1], n[2])?;
        writeln!(w, "    outer loop")?;
        for p in [a, b, c] {
            writeln!(w, "      vertex {:.16e} {:.16e} {:.16e}", p[0], p[1], p[2])?;
        }
        writeln!(w, "    endloop")?;
        writeln!(w, "  endfacet")?;
    }
    writeln!(w, "endsolid {name}")
}

/// A polyhedral sphere: the icosahedron with its triangles split into four `level` times and
/// the vertices pushed onto the sphere of centre `c` and radius `r` (20 · 4^level triangles,
/// outward oriented; every vertex lies on the sphere, so the polyhedron is inscribed). Used
/// by the tests and the STL example.
pub fn icosphere(c: [f64; 3], r: f64, level: usize) -> Vec<[[f64; 3]; 3]> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let f: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let unit = |p: [f64; 3]| {
        let l = dot(p, p).sqrt();
        p.map(|x| x / l)
    };
    let mut tris: Vec<[[f64; 3]; 3]> = f.iter().map(|t| t.map(|i| unit(v[i]))).collect();
    for _ in 0..level {
        let mut next = Vec::with_capacity(4 * tris.len());
        for [a, b, c] in tris {
            let m = |p: [f64; 3], q: [f64; 3]| unit([p[0] + q[0], p[1] + q[1], p[2] + q[2]]);
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    tris.iter()
        .map(|t| t.map(|p| [c[0] + r * p[0], c[1] + r * p[1], c[2] + r * p[2]]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// The cube c + [−h, h]³ as 12 outward triangles.
    fn cube(c: [f64; 3], h: [f64; 3]) -> Vec<[[f64; 3]; 3]> {
        let p = |i: usize| {
            let s = |b: usize, k: usize| {
                if i >> b & 1 == 1 {
                    c[k] + h[k]
                } else {
                    c[k] - h[k]
                }
            };
            [s(0, 0), s(1, 1), s(2, 2)]
        };
        // Faces as quads (counter-clockwise seen from outside), split into two triangles.
        let quads = [
            [0, 2, 3, 1], // z−
            [4, 5, 7, 6], // z+
            [0, 1, 5, 4], // y−
            [2, 6, 7, 3], // y+
            [0, 4, 6, 2], // x−
            [1, 3, 7, 5], // x+
        ];
        quads
            .iter()
            .flat_map(|q| [[p(q[0]), p(q[1]), p(q[2])], [p(q[0]), p(q[2]), p(q[3])]])
            .collect()
    }

    /// Exact signed distance of x to the box c + [−h, h]³.
    fn box_sdf(c: [f64; 3], h: [f64; 3], x: [f64; 3]) -> f64 {
        let q: Vec<f64> = (0..3).map(|k| (x[k] - c[k]).abs() - h[k]).collect();
        let out = q.iter().map(|v| v.max(0.0).powi(2)).sum::<f64>().sqrt();
        out + q.iter().cloned().fold(f64::NEG_INFINITY, f64::max).min(0.0)
    }

    fn norm(a: [f64; 3]) -> f64 {
        dot(a, a).sqrt()
    }

    #[test]
    fn cube_exact_on_both_sides() {
        let (c, h) = ([0.3, -0.2, 1.0], [1.0, 0.5, 0.25]);
        let s = TriSurface::from_triangles(&cube(c, h)).unwrap();
        assert!((s.volume() - 8.0 * h[0] * h[1] * h[2]).abs() < 1e-14);
        let mut rng = StdRng::seed_from_u64(7);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..2000 {
            let x: [f64; 3] = std::array::from_fn(|k| c[k] + rng.gen_range(-2.0..2.0) * h[k]);
            let q = s.project(x);
            let g = box_sdf(c, h, x);
            // The box's faces are exact in the file: the distance is exact up to round-off of
            // the unit-size coordinates.
            assert!((q.gap - g).abs() < 1e-13, "gap {} vs {g} at {x:?}", q.gap);
            assert!((norm(q.normal) - 1.0).abs() < 1e-14);
            for k in 0..3 {
                assert!((x[k] - q.closest[k] - q.gap * q.normal[k]).abs() < 1e-13);
            }
            // The closest point is on the surface of the box.
            assert!(box_sdf(c, h, q.closest).abs() < 1e-13);
            // Where the exact distance is differentiable (its one-sided differences agree), its
            // gradient is n.
            let e = 1e-6;
            let fd = |k: usize, t: f64| {
                let mut y = x;
                y[k] += t;
                (box_sdf(c, h, y) - g) / t
            };
            let smooth = (0..3).all(|k| (fd(k, e) - fd(k, -e)).abs() < 1e-6);
            if smooth {
                for k in 0..3 {
                    let (mut y, mut z) = (x, x);
                    y[k] += e;
                    z[k] -= e;
                    let d = (s.project(y).gap - s.project(z).gap) / (2.0 * e);
                    assert!(
                        (d - q.normal[k]).abs() < 1e-6,
                        "dg/dx{k} {d} vs n {:?}",
                        q.normal
                    );
                }
            }
            if g < 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(
            inside > 100 && outside > 100,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn icosphere_within_its_chord_error() {
        let (c, r) = ([0.1, 0.2, 1.3], 0.8);
        let tris = icosphere(c, r, 3);
        // The sagitta: the largest distance between the sphere and a face plane. The inscribed
        // polyhedron P lies between the balls of radii r − sag and r, so its signed distance
        // lies between theirs: g_sphere ≤ g_P ≤ g_sphere + sag.
        let mut sag: f64 = 0.0;
        let mut alpha: f64 = 0.0;
        for [a, b, cc] in &tris {
            let n = cross(sub(*b, *a), sub(*cc, *a));
            let n = n.map(|v| v / norm(n));
            sag = sag.max(r - dot(sub(*a, c), n));
            for p in [a, b, cc] {
                let rad = sub(*p, c).map(|v| v / r);
                alpha = alpha.max(dot(rad, n).min(1.0).acos());
            }
        }
        assert!(sag > 0.0 && sag < 0.01 * r, "sag {sag}");
        let s = TriSurface::from_triangles(&tris).unwrap();
        let exact_volume = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!(s.volume() < exact_volume && s.volume() > exact_volume * (1.0 - 3.0 * sag / r));
        let mut rng = StdRng::seed_from_u64(11);
        for i in 0..2000 {
            let dir: [f64; 3] = std::array::from_fn(|_| rng.gen_range(-1.0..1.0));
            if norm(dir) < 0.1 {
                continue;
            }
            let rad = dir.map(|v| v / norm(dir));
            let rho = r * if i % 2 == 0 {
                rng.gen_range(0.5..0.999)
            } else {
                rng.gen_range(1.001..1.5)
            };
            let x: [f64; 3] = std::array::from_fn(|k| c[k] + rho * rad[k]);
            let q = s.project(x);
            let g = rho - r;
            assert!(
                q.gap >= g - 1e-12 && q.gap <= g + sag + 1e-12,
                "gap {} vs sphere {g} (sag {sag}) at {x:?}",
                q.gap
            );
            for k in 0..3 {
                assert!((x[k] - q.closest[k] - q.gap * q.normal[k]).abs() < 1e-12);
            }
            let y = norm(sub(q.closest, c));
            assert!(
                y <= r + 1e-12 && y >= r - sag - 1e-12,
                "closest at radius {y}"
            );
            // n lies in the normal cone of the nearest face, edge or vertex: within the facets'
            // angle of the radial direction (twice, for x and the feature's own radials).
            let angle = dot(q.normal, rad).min(1.0).acos();
            assert!(
                angle <= 2.0 * alpha,
                "normal {angle} rad off radial (alpha {alpha})"
            );
        }
    }

    fn stl_round_trip(tris: &[[[f64; 3]; 3]]) -> Vec<[[f64; 3]; 3]> {
        let mut text = Vec::new();
        write_stl_ascii(&mut text, "t", tris).unwrap();
        parse_stl(&text).unwrap()
    }

    #[test]
    fn stl_ascii_and_binary() {
        let tris = icosphere([0.0; 3], 1.0, 1);
        assert_eq!(stl_round_trip(&tris), tris);
        // Binary: 80 bytes of header (here starting with "solid", as some writers do), the
        // count, 50 bytes per triangle (f32).
        let mut b = b"solid but binary".to_vec();
        b.resize(80, b' ');
        b.extend((tris.len() as u32).to_le_bytes());
        for t in &tris {
            b.extend([0u8; 12]);
            for p in t {
                for v in p {
                    b.extend((*v as f32).to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        let back = parse_stl(&b).unwrap();
        assert_eq!(back.len(), tris.len());
        for (t, u) in tris.iter().zip(&back) {
            for k in 0..3 {
                for j in 0..3 {
                    assert_eq!(u[k][j], t[k][j] as f32 as f64);
                }
            }
        }
        // f32 rounding keeps shared vertices identical: the binary surface is closed too.
        let s = TriSurface::from_triangles(&back).unwrap();
        assert_eq!(s.num_triangles(), 80);
    }

    #[test]
    fn bad_stl_text() {
        let e = |t: &str| parse_stl(t.as_bytes()).unwrap_err();
        assert!(e("").contains("empty"));
        assert!(
            e("hello\n").contains("starts with 'solid'"),
            "{}",
            e("hello\n")
        );
        let one = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                   endloop\nendfacet\nendsolid s\n";
        assert!(e(one).contains("line 3: a facet needs 3 vertices, this one has 2"));
        let bad = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 x\n";
        assert!(e(bad).contains("line 4: 'vertex' needs three numbers"));
        assert!(e("solid s\nfacet normal 0 0 1\n").contains("no 'endsolid'"));
        assert!(parse_stl(&[0xff, 0xfe, 0x00])
            .unwrap_err()
            .contains("neither binary"));
    }

    #[test]
    fn a_directory_or_device_is_not_read() {
        let dir = std::env::temp_dir();
        let e = TriSurface::read_stl(&dir).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        let e = TriSurface::read_stl(Path::new("/dev/zero")).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn bad_surfaces() {
        let good = cube([0.0; 3], [1.0; 3]);
        let err = |t: &[[[f64; 3]; 3]]| TriSurface::from_triangles(t).unwrap_err();
        let mut open = good.clone();
        open.pop();
        assert!(err(&open).contains("not closed"), "{}", err(&open));
        let mut flipped_one = good.clone();
        flipped_one[3].swap(1, 2);
        assert!(err(&flipped_one).contains("oriented inconsistently"));
        let inside_out: Vec<_> = good.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let m = err(&inside_out);
        assert!(m.contains("inside-out") && m.contains("flip"), "{m}");
        let mut degenerate = good.clone();
        degenerate[5] = [good[5][0], good[5][0], good[5][1]];
        assert!(err(&degenerate).contains("triangle 6 is degenerate"));
        let mut twice = good.clone();
        twice.extend(good.iter().take(2).cloned());
        assert!(err(&twice).contains("shared by 3"), "{}", err(&twice));
        let mut nan = good.clone();
        nan[0][1][2] = f64::NAN;
        assert!(err(&nan).contains("triangle 1 has a coordinate"));
        assert!(err(&[]).contains("no triangles"));
    }
}
