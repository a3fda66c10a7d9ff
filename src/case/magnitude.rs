//! The magnitudes a case can have (docs/case-file.md, "Units"). The problem is linear in its
//! data but for the contact conditions, which are homogeneous, so any consistent unit system
//! gives the same solution in its units; what a unit system cannot change is the range of
//! double precision. The solver squares its scales (norms, Gram matrices, the dense
//! compliance, squared distances) and sums such squares over the unknowns, and it forms cell
//! measures and their squares from the coordinates; a scale whose square leaves the normal
//! doubles (or whose sum over the unknowns overflows) ends in an overflow, an underflow to
//! zero or a loss of every significant digit, deep inside a solve. Each scale is therefore
//! checked before anything is assembled, against a range derived from the double-precision
//! limits and the problem's size alone ([`admissible`]), and an error names the key.

use super::body::{BodyForceSpec, Load};
use super::contact::{Friction, Motion};
use super::file::Case;
use super::shape::ObstacleSpec;
use super::tree::{join_index, join_key};
use crate::error::InputError;

/// Room left above the sum of a scale's squares over the unknowns: the solver multiplies
/// such sums by the few further factors of its tolerances and combinations (a 1e-12 or 1e12,
/// a sum of a handful of terms), none beyond 2^32. Not measured; not machine-specific (double
/// precision's range).
const HEADROOM: f64 = 4_294_967_296.0;

/// The range [lo, hi] of a scale x that the solver forms to the power `p` and sums over `n`
/// unknowns: x^p a normal double with all its 53 bits (x^p ≥ MIN_POSITIVE / ε) and
/// n x^p ≤ MAX / [`HEADROOM`]. Lengths enter as p = 2d (the squares of cell measures), every
/// other scale as p = 2. Pure.
pub fn admissible(p: i32, n: usize) -> (f64, f64) {
    let p = f64::from(p);
    let lo = (f64::MIN_POSITIVE / f64::EPSILON).powf(1.0 / p);
    let hi = (f64::MAX / (HEADROOM * n.max(1) as f64)).powf(1.0 / p);
    (lo, hi)
}

/// The largest |x| of a list (0 for none).
fn largest(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The largest |component| of a motion or force: its value or every row of its table.
fn motion_size(m: &Motion) -> f64 {
    m.table
        .iter()
        .map(|(_, row)| largest(row))
        .fold(largest(&m.value), f64::max)
}

/// The lengths of an obstacle's geometry, by key: the largest |coordinate| of its points and
/// its radii (axes and normals are directions, angles have no unit).
fn shape_lengths(shape: &ObstacleSpec) -> Vec<(&'static str, f64)> {
    match shape {
        ObstacleSpec::Plane { point, .. } => vec![("point", largest(point))],
        ObstacleSpec::Sphere { center, radius } => {
            vec![("center", largest(center)), ("radius", *radius)]
        }
        ObstacleSpec::Cylinder { point, radius, .. } => {
            vec![("point", largest(point)), ("radius", *radius)]
        }
        ObstacleSpec::Cone { apex, .. } | ObstacleSpec::Pyramid { apex, .. } => {
            vec![("apex", largest(apex))]
        }
        ObstacleSpec::Punch {
            center,
            radius,
            edge_radius,
            ..
        } => vec![
            ("center", largest(center)),
            ("radius", *radius),
            ("edge_radius", *edge_radius),
        ],
        ObstacleSpec::Height { .. } | ObstacleSpec::Surface { .. } | ObstacleSpec::Body { .. } => {
            Vec::new()
        }
    }
}

/// One scale of the problem and the value of the case it comes from.
struct Scale<'a> {
    /// The case's key and its value.
    key: String,
    value: f64,
    /// What the scale is (for the message), e.g. "the stiffness E L^(d−2)".
    what: &'a str,
    scale: f64,
    /// The power the solver forms it to: 2d for lengths, 2 otherwise.
    power: i32,
}

/// The softest material: its key, E and E L^(d−2).
type Softest = (String, f64, f64);

/// One load as a nodal force: the case's key and value, the force and what it is.
struct NodalLoad {
    key: String,
    value: f64,
    force: f64,
    what: &'static str,
}

impl Case {
    /// The mesh's lengths against their range ([`admissible`] with p = 2d, `n` unknowns):
    /// its extent (the largest side of its bounding box) and its largest |coordinate|.
    /// Checked before any cell is measured: a mesh in units where its cells' areas underflow
    /// would otherwise be refused as degenerate. Pure.
    pub fn check_mesh_lengths(
        &self,
        dim: usize,
        extent: f64,
        far: f64,
        n: usize,
    ) -> Result<(), InputError> {
        let (lo, hi) = admissible(2 * dim as i32, n);
        for (what, x) in [
            ("extent (the largest side of its bounding box)", extent),
            ("largest |coordinate|", far),
        ] {
            if x > 0.0 && !(lo..=hi).contains(&x) {
                return Err(self.err_at(
                    "mesh.file",
                    format!(
                        "the mesh's {what} is {x:.3e}, outside the range this solver can \
                         represent for a {dim}D length: {lo:.1e} … {hi:.1e} (its {}th power, the \
                         square of a cell measure, must be a normal double and its sum over \
                         the {n} unknowns must not overflow); give the case in other units \
                         (docs/case-file.md, \"Units\")",
                        2 * dim
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every scale of the case against its range ([`admissible`]): with L the mesh's extent,
    /// the stiffness E L^(d−2) of each material, each load as a nodal force (a pressure,
    /// traction or Tresca threshold times L^(d−1), a body force times L^d, a prescribed
    /// force), each prescribed displacement (Dirichlet values, motions), the obstacles'
    /// lengths, a given `newton.c` (a stiffness), and the displacement the largest load
    /// causes in the softest material, F / (E L^(d−2)). Zeros are not scales. The first scale
    /// out of its range is an error naming its key (in that order). Pure.
    pub fn check_magnitudes(&self, dim: usize, extent: f64, n: usize) -> Result<(), InputError> {
        let d = dim as i32;
        let (mut scales, softest) = self.material_scales(d, extent);
        scales.extend(self.displacement_scales(d));
        let loads = self.nodal_loads(d, extent);
        scales.extend(loads.iter().map(|f| Scale {
            key: f.key.clone(),
            value: f.value,
            what: f.what,
            scale: f.force,
            power: 2,
        }));
        if let Some(c) = self.newton.c {
            scales.push(Scale {
                key: "newton.c".into(),
                value: c,
                what: "the complementarity parameter (a stiffness)",
                scale: c,
                power: 2,
            });
        }
        for s in &scales {
            self.check_scale(s, dim, n)?;
        }
        self.check_displacement(&loads, softest, extent, n)
    }

    /// Each material's stiffness E L^(d−2), and the softest one (key, E, E L^(d−2)). Pure.
    fn material_scales(&self, d: i32, l: f64) -> (Vec<Scale<'static>>, Option<Softest>) {
        let mut scales = Vec::new();
        let mut softest: Option<Softest> = None;
        for m in &self.materials {
            let k = m.young * l.powi(d - 2);
            if softest.as_ref().is_none_or(|s| k < s.2) {
                softest = Some((join_key(&m.key, "young"), m.young, k));
            }
            scales.push(Scale {
                key: join_key(&m.key, "young"),
                value: m.young,
                what: "the stiffness E L^(d−2)",
                scale: k,
                power: 2,
            });
        }
        (scales, softest)
    }

    /// The prescribed displacements (Dirichlet values), then each contact pair's obstacle
    /// lengths and motion. Pure.
    fn displacement_scales(&self, d: i32) -> Vec<Scale<'static>> {
        let mut scales = Vec::new();
        for (i, dr) in self.dirichlet.iter().enumerate() {
            let v = dr
                .value
                .iter()
                .flatten()
                .fold(0.0f64, |m, x| m.max(x.abs()));
            scales.push(Scale {
                key: join_key(&join_index("dirichlet", i), "value"),
                value: v,
                what: "a prescribed displacement",
                scale: v,
                power: 2,
            });
        }
        for c in &self.contacts {
            for (name, x) in shape_lengths(&c.obstacle) {
                scales.push(Scale {
                    key: join_key(&join_key(&c.key, "obstacle"), name),
                    value: x,
                    what: "a length of the obstacle",
                    scale: x,
                    power: 2 * d,
                });
            }
            if let Some(m) = &c.motion {
                let v = motion_size(m);
                scales.push(Scale {
                    key: m.key.clone(),
                    value: v,
                    what: "the obstacle's motion",
                    scale: v,
                    power: 2,
                });
            }
        }
        scales
    }

    /// Each load as a nodal force: Neumann data, a constant body force, each pair's
    /// prescribed force and Tresca threshold. Pure.
    fn nodal_loads(&self, d: i32, l: f64) -> Vec<NodalLoad> {
        let mut loads = Vec::new();
        for (i, nm) in self.neumann.iter().enumerate() {
            let (name, v) = match &nm.load {
                Load::Pressure(p) => ("pressure", p.abs()),
                Load::Traction(t) => ("traction", largest(t)),
            };
            loads.push(NodalLoad {
                key: join_key(&join_index("neumann", i), name),
                value: v,
                force: v * l.powi(d - 1),
                what: "a nodal force (the traction times L^(d−1))",
            });
        }
        if let Some(BodyForceSpec::Constant(v)) = &self.body_force {
            let b = largest(v);
            loads.push(NodalLoad {
                key: "body_force.value".into(),
                value: b,
                force: b * l.powi(d),
                what: "a nodal force (the force per volume times L^d)",
            });
        }
        for c in &self.contacts {
            if let Some(f) = &c.force {
                let v = motion_size(f);
                loads.push(NodalLoad {
                    key: f.key.clone(),
                    value: v,
                    force: v,
                    what: "a force",
                });
            }
            if let Friction::Tresca { threshold } = c.friction {
                loads.push(NodalLoad {
                    key: join_key(&join_key(&c.key, "friction"), "threshold"),
                    value: threshold,
                    force: threshold * l.powi(d - 1),
                    what: "a nodal threshold (the threshold times L^(d−1))",
                });
            }
        }
        loads
    }

    /// The displacement the largest load causes in the softest material, F / (E L^(d−2)),
    /// against its range. Pure.
    fn check_displacement(
        &self,
        loads: &[NodalLoad],
        softest: Option<Softest>,
        l: f64,
        n: usize,
    ) -> Result<(), InputError> {
        let heaviest = loads.iter().max_by(|a, b| a.force.total_cmp(&b.force));
        let (Some(load), Some((ek, ev, k))) = (heaviest, softest) else {
            return Ok(());
        };
        let (lk, lv) = (&load.key, load.value);
        let u = load.force / k;
        let (lo, hi) = admissible(2, n);
        if u > 0.0 && !(lo..=hi).contains(&u) {
            return Err(self.err_at(
                lk,
                format!(
                    "{lv:e} with {ek} = {ev:e} gives displacements of about {u:.3e} \
                     (F / (E L^(d−2)), L = {l:.3e} the mesh's extent), outside the range \
                     this solver can represent: {lo:.1e} … {hi:.1e} (the square of a scale, \
                     summed over the {n} unknowns, must be a normal double); give the case \
                     in other units (docs/case-file.md, \"Units\")"
                ),
            ));
        }
        Ok(())
    }

    /// One scale against its range; an error names its key and value. Pure.
    fn check_scale(&self, s: &Scale, dim: usize, n: usize) -> Result<(), InputError> {
        let (lo, hi) = admissible(s.power, n);
        if s.scale == 0.0 || (lo..=hi).contains(&s.scale) {
            return Ok(());
        }
        let what = if s.scale == s.value {
            String::new()
        } else {
            format!(" makes {} {:.3e}", s.what, s.scale)
        };
        let unit = if s.power == 2 {
            "the square of a scale, summed over the".to_string()
        } else {
            format!(
                "the {}th power of a {dim}D length (the square of a cell measure), summed over \
                 the",
                s.power
            )
        };
        Err(self.err_at(
            &s.key,
            format!(
                "{:e}{what}, outside the range this solver can represent{}: {lo:.1e} … {hi:.1e} \
                 ({unit} {n} unknowns, must be a normal double); give the case in other units \
                 (docs/case-file.md, \"Units\")",
                s.value,
                if what.is_empty() {
                    format!(" for {}", s.what)
                } else {
                    String::new()
                }
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_range_follows_double_precision_and_the_size() {
        let (lo, hi) = admissible(2, 1);
        assert!((lo * lo / (f64::MIN_POSITIVE / f64::EPSILON) - 1.0).abs() < 1e-12);
        assert!((hi * hi * HEADROOM / f64::MAX - 1.0).abs() < 1e-12);
        // a million unknowns take 3 decades off the top of a squared scale
        let (_, hi6) = admissible(2, 1_000_000);
        assert!((hi / hi6 - 1e3).abs() < 1e-6 * 1e3);
        // lengths in 3D: their 6th power
        let (l3, h3) = admissible(6, 1);
        assert!(
            l3 > 1e-50 && l3 < 1e-48 && h3 > 1e49 && h3 < 1e50,
            "{l3:e} {h3:e}"
        );
    }
}
