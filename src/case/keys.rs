//! The keys the case file accepts, table by table: the reader checks every table against its
//! list here (a key not in the list is an input error that names the allowed keys), and
//! docs/case-file.md documents the same lists (tests/case_file_doc.rs compares both ways).

/// The top level: the sections.
pub const ROOT: &[&str] = &[
    "mesh",
    "material",
    "dirichlet",
    "neumann",
    "body_force",
    "solver",
    "output",
    "contact",
    "newton",
    "load",
];
/// `[mesh]`.
pub const MESH: &[&str] = &["file", "refine", "project"];
/// `[[mesh.project]]`.
pub const MESH_PROJECT: &[&str] = &["group", "shape"];
/// `[material]`.
pub const MATERIAL: &[&str] = &["young", "poisson", "model"];
/// Each `[[material]]` (one per volume group).
pub const MATERIALS: &[&str] = &["group", "young", "poisson", "model"];
/// `[[dirichlet]]`.
pub const DIRICHLET: &[&str] = &["group", "value", "ramp"];
/// `[[neumann]]`.
pub const NEUMANN: &[&str] = &["group", "pressure", "traction", "ramp"];
/// `[body_force]`.
pub const BODY_FORCE: &[&str] = &["value", "expr"];
/// `[contact]` and each `[[contact]]`.
pub const CONTACT: &[&str] = &[
    "group",
    "obstacle",
    "motion",
    "force",
    "friction",
    "rigid_modes",
];
/// `contact.motion` or `contact.force` given as a table.
pub const MOTION: &[&str] = &["value", "ramp", "table"];
/// The obstacles (`contact.obstacle`, `[[mesh.project]] shape`), by `type`.
pub const PLANE: &[&str] = &["type", "point", "normal"];
pub const SPHERE: &[&str] = &["type", "center", "radius"];
/// `type = "body"`: another body of the mesh, its boundary group (dual mortar).
pub const BODY: &[&str] = &["type", "group"];
pub const CYLINDER: &[&str] = &["type", "point", "axis", "radius"];
pub const CONE: &[&str] = &["type", "apex", "axis", "half_angle"];
pub const PYRAMID: &[&str] = &["type", "apex", "axis", "half_angle", "faces", "azimuth"];
pub const PUNCH: &[&str] = &["type", "center", "axis", "radius", "edge_radius"];
pub const HEIGHT: &[&str] = &["type", "expr"];
pub const SURFACE: &[&str] = &["type", "file"];
/// `contact.friction` as a table, by `law` (the keys of any law are read first, then the
/// law's own).
pub const FRICTION_ANY: &[&str] = &["law", "threshold", "mu", "algorithm"];
pub const FRICTION_NONE: &[&str] = &["law"];
pub const FRICTION_TRESCA: &[&str] = &["law", "threshold"];
pub const FRICTION_COULOMB: &[&str] = &["law", "mu", "algorithm"];
/// `[newton]`.
pub const NEWTON: &[&str] = &["init", "c", "max_steps", "tol_u", "on_cycle", "strict"];
/// `[solver]`.
pub const SOLVER: &[&str] = &[
    "preset",
    "method",
    "petsc_options",
    "rtol",
    "path",
    "reuse",
    "repeatable",
    "dense_threads",
];
/// `[load]`.
pub const LOAD: &[&str] = &["steps", "factors", "max_cutbacks"];
/// `[output]`.
pub const OUTPUT: &[&str] = &["dir", "fields"];

/// Every table of the case file with its keys, named as docs/case-file.md's headings name
/// them (FRICTION_ANY, the union of the laws' keys, is not a table of its own).
pub const SECTIONS: &[(&str, &[&str])] = &[
    ("top level", ROOT),
    ("[mesh]", MESH),
    ("[[mesh.project]]", MESH_PROJECT),
    ("[material]", MATERIAL),
    ("[[material]]", MATERIALS),
    ("[[dirichlet]]", DIRICHLET),
    ("[[neumann]]", NEUMANN),
    ("[body_force]", BODY_FORCE),
    ("[contact]", CONTACT),
    ("motion = { }", MOTION),
    ("type = \"plane\"", PLANE),
    ("type = \"sphere\"", SPHERE),
    ("type = \"cylinder\"", CYLINDER),
    ("type = \"cone\"", CONE),
    ("type = \"pyramid\"", PYRAMID),
    ("type = \"punch\"", PUNCH),
    ("type = \"height\"", HEIGHT),
    ("type = \"surface\"", SURFACE),
    ("type = \"body\"", BODY),
    ("law = \"none\"", FRICTION_NONE),
    ("law = \"tresca\"", FRICTION_TRESCA),
    ("law = \"coulomb\"", FRICTION_COULOMB),
    ("[newton]", NEWTON),
    ("[solver]", SOLVER),
    ("[load]", LOAD),
    ("[output]", OUTPUT),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The keys read before the law is known are exactly those of the laws together.
    #[test]
    fn friction_any_is_the_union_of_the_laws() {
        let mut union: Vec<&str> = [FRICTION_NONE, FRICTION_TRESCA, FRICTION_COULOMB].concat();
        union.sort_unstable();
        union.dedup();
        let mut any = FRICTION_ANY.to_vec();
        any.sort_unstable();
        assert_eq!(any, union);
    }
}
