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
        if let Some(t) = tris.iter().position(|t| t.iter().flatten().any(|v| !v.is_finite())) {
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
        let vertices: Vec<Vector> = verts.iter().map(|p| Vector::new(p[0], p[1], p[2])).collect();
        let mesh = TriMesh::with_flags(vertices, idx, TriMeshFlags::ORIENTED)
            .map_err(|e| format!("the triangle mesh could not be built: {e}"))?;
        Ok(TriSurface { mesh, size, volume })
    }

    /// Reads and checks an STL file (ASCII or binary).
    pub fn read_stl(path: &Path) -> Result<Self, String> {
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
