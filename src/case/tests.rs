//! Unit tests of the case file: every rejection names the key and its line.

use super::*;
use crate::error::InputError;
use std::path::Path;

const FILE: &str = "/cases/plate.toml";

const MINIMAL: &str = r#"[mesh]
file = "meshes/plate.msh"

[material]
young = 2.0
poisson = 0.3
model = "plane_strain"
"#;

const FULL: &str = r#"# a full case
[mesh]
file = "meshes/plate.msh"

[material]
young = 210
poisson = 0.25
model = "plane_stress"

[[dirichlet]]
group = "clamp"
value = [0.0, 0.0]

[[dirichlet]]
group = "roller"
value = ["free", -0.5]

[[neumann]]
group = "load"
pressure = 0.02

[[neumann]]
group = "side"
traction = [1, -0.02]

[body_force]
value = [0.0, -9.81]

[solver]
preset = "iterative"
petsc_options = "-ksp_monitor"
rtol = 1e-8

[output]
dir = "out/somewhere"
fields = ["displacement", "stress", "von_mises", "von_mises_thesis", "rank", "body", "contact", "stress"]

[contact]
group = "contact"
obstacle = { type = "plane", point = [0.0, -1.0], normal = [3.0, 4.0] }
friction = { law = "tresca", threshold = 0.01 }
rigid_modes = "none"

[newton]
init = "gap"
c = 10
max_steps = 7
tol_u = 1e-12
"#;

fn parse(text: &str) -> Result<Case, InputError> {
    Case::parse(text, Path::new(FILE), &[], None)
}

fn parse_set(text: &str, sets: &[&str]) -> Result<Case, InputError> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Case::parse(text, Path::new(FILE), &sets, None)
}

/// 1-based line of the first line of `text` that contains `needle` (found independently of
/// the implementation, by plain text search).
fn line(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("test bug: '{needle}' not in text"))
        + 1
}

/// Asserts an error with the given key and line; returns it for message checks.
fn expect_err(text: &str, key: &str, line_needle: &str) -> InputError {
    let e = parse(text).expect_err("should be rejected");
    assert_eq!(e.file, Path::new(FILE), "{e}");
    assert_eq!(e.key.as_deref(), Some(key), "{e}");
    assert_eq!(e.line, Some(line(text, line_needle)), "{e}");
    let shown = e.to_string();
    assert!(shown.contains(key), "{shown}");
    assert!(!shown.contains('\n'), "one line: {shown}");
    e
}

fn with(extra: &str) -> String {
    format!("{MINIMAL}{extra}")
}

fn replace(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "test bug: '{from}'");
    text.replacen(from, to, 1)
}

#[test]
fn full_file_round_trip() {
    let c = parse(FULL).unwrap();
    assert_eq!(c.file, Path::new(FILE));
    assert_eq!(c.mesh.file, Path::new("/cases/meshes/plate.msh"));
    assert_eq!(c.materials[0].young, 210.0);
    assert_eq!(c.materials[0].poisson, 0.25);
    assert_eq!(c.materials[0].model, Some(MaterialModel::PlaneStress));
    assert_eq!(
        c.dirichlet,
        vec![
            Dirichlet {
                group: "clamp".into(),
                value: vec![Some(0.0), Some(0.0)],
                ramp: true,
            },
            Dirichlet {
                group: "roller".into(),
                value: vec![None, Some(-0.5)],
                ramp: true,
            },
        ]
    );
    assert_eq!(
        c.neumann,
        vec![
            Neumann {
                group: "load".into(),
                load: Load::Pressure(0.02),
                ramp: true,
            },
            Neumann {
                group: "side".into(),
                load: Load::Traction(vec![1.0, -0.02]),
                ramp: true,
            },
        ]
    );
    assert_eq!(
        c.body_force,
        Some(BodyForceSpec::Constant(vec![0.0, -9.81]))
    );
    assert_eq!(c.solver.preset, Preset::Iterative);
    assert_eq!(c.solver.petsc_options, "-ksp_monitor");
    assert_eq!(c.solver.rtol, 1e-8);
    assert_eq!(c.output.dir, Path::new("out/somewhere"));
    // Duplicates dropped, order kept.
    assert_eq!(c.output.fields, OutputField::ALL.to_vec());
    assert!(c.output.wants(OutputField::Rank));
    let contact = c.contacts.first().unwrap();
    assert_eq!(contact.group, "contact");
    match &contact.obstacle {
        ObstacleSpec::Plane { point, normal } => {
            assert_eq!(point, &vec![0.0, -1.0]);
            assert!((normal[0] - 0.6).abs() < 1e-15 && (normal[1] - 0.8).abs() < 1e-15);
        }
        o => panic!("{o:?}"),
    }
    assert_eq!(contact.friction, Friction::Tresca { threshold: 0.01 });
    assert_eq!(contact.rigid_modes, RigidModeHandling::None);
    assert_eq!(c.newton.init, NewtonInit::Gap);
    assert_eq!(c.newton.c, Some(10.0));
    assert_eq!(c.newton.max_steps, 7);
    assert_eq!(c.newton.tol_u, 1e-12);
    // Lines of keys are remembered.
    assert_eq!(
        c.line_of("dirichlet[1].value"),
        Some(line(FULL, "\"free\""))
    );
    assert_eq!(
        c.line_of("contact.group"),
        Some(line(FULL, "group = \"contact\""))
    );
    assert_eq!(c.model(2).unwrap(), MaterialModel::PlaneStress);
}

#[test]
fn minimal_file_gets_defaults() {
    let c = parse(MINIMAL).unwrap();
    assert!(c.dirichlet.is_empty() && c.neumann.is_empty());
    assert_eq!(c.body_force, None);
    assert_eq!(c.solver, SolverSection::default());
    assert_eq!(c.solver.preset, Preset::Auto);
    assert_eq!(c.solver.petsc_options, "");
    assert_eq!(c.solver.rtol, 1e-10);
    assert_eq!(c.solver.reuse, Reuse::Auto);
    assert_eq!(c.output.dir, Path::new("out/plate"));
    assert_eq!(
        c.output.fields,
        vec![
            OutputField::Displacement,
            OutputField::VonMises,
            OutputField::Contact
        ]
    );
    assert!(!c.output.wants(OutputField::Stress));
    assert!(c.contacts.is_empty());
    assert_eq!(c.newton.init, NewtonInit::Auto);
    assert_eq!(c.newton.c, None);
    assert_eq!(c.newton.max_steps, 100);
    assert_eq!(c.newton.tol_u, 1e-10);
    assert!(!c.newton.strict);
}

#[test]
fn contact_defaults_and_sphere() {
    let c = parse(&with(
        "[contact]\ngroup = \"c\"\n[contact.obstacle]\ntype = \"sphere\"\ncenter = [0, 1.5, 0]\nradius = 0.5\n",
    ))
    .unwrap();
    let k = c.contacts.into_iter().next().unwrap();
    assert_eq!(k.friction, Friction::None);
    assert_eq!(k.rigid_modes, RigidModeHandling::Auto);
    assert_eq!(
        k.obstacle,
        ObstacleSpec::Sphere {
            center: vec![0.0, 1.5, 0.0],
            radius: 0.5
        }
    );
    let c = parse(&with(
        "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, -2] }\nfriction = \"none\"\n",
    ))
    .unwrap();
    assert_eq!(
        c.contacts.into_iter().next().unwrap().friction,
        Friction::None
    );
}

#[test]
fn reject_syntax_error_with_line() {
    let text = with("[newton]\nc = = 3\n");
    let e = parse(&text).unwrap_err();
    assert_eq!(e.line, Some(line(&text, "c = = 3")), "{e}");
    assert!(e.message.contains("syntax"), "{e}");
    assert!(!e.to_string().contains('\n'), "{e}");
}

#[test]
fn reject_duplicate_key_as_syntax_error() {
    let text = replace(MINIMAL, "poisson = 0.3", "poisson = 0.3\npoisson = 0.2");
    let e = parse(&text).unwrap_err();
    assert_eq!(e.line, Some(line(&text, "poisson = 0.2")), "{e}");
}

#[test]
fn reject_unknown_top_level_key() {
    let e = expect_err(&with("[solvr]\npreset = \"direct\"\n"), "solvr", "[solvr]");
    assert!(
        e.message.contains("allowed keys") && e.message.contains("solver"),
        "{e}"
    );
}

#[test]
fn reject_unknown_key_in_section() {
    let e = expect_err(
        &replace(MINIMAL, "young", "youngs"),
        "material.youngs",
        "youngs",
    );
    assert!(e.message.contains("young, poisson, model"), "{e}");
}

#[test]
fn reject_unknown_key_in_array_of_tables() {
    let text = with("[[dirichlet]]\ngroup = \"a\"\nvalue = [0, 0]\n\n[[dirichlet]]\ngroup = \"b\"\nvalues = [0, 0]\n");
    expect_err(&text, "dirichlet[1].values", "values");
}

#[test]
fn reject_wrong_types() {
    let e = expect_err(
        &replace(MINIMAL, "2.0", "\"two\""),
        "material.young",
        "young",
    );
    assert!(
        e.message.contains("number") && e.message.contains("string"),
        "{e}"
    );
    expect_err(
        &with("[newton]\nmax_steps = 1.5\n"),
        "newton.max_steps",
        "max_steps",
    );
    expect_err(
        &replace(MINIMAL, "\"meshes/plate.msh\"", "3"),
        "mesh.file",
        "file",
    );
    expect_err(
        &with("[dirichlet]\ngroup = \"a\"\n"),
        "dirichlet",
        "[dirichlet]",
    );
    expect_err(
        &with("[output]\nfields = \"stress\"\n"),
        "output.fields",
        "fields",
    );
    expect_err(
        &with("[solver]\npetsc_options = 1\n"),
        "solver.petsc_options",
        "petsc",
    );
    expect_err(
        &replace(MINIMAL, "[mesh]\nfile = \"meshes/plate.msh\"", "mesh = 1"),
        "mesh",
        "mesh = 1",
    );
}

#[test]
fn reject_missing_required_key_at_section_line() {
    let text = replace(MINIMAL, "young = 2.0\n", "");
    let e = expect_err(&text, "material.young", "[material]");
    assert!(e.message.contains("missing"), "{e}");
    let text = with("[[neumann]]\npressure = 1.0\n");
    expect_err(&text, "neumann[0].group", "[[neumann]]");
    let text = with("[contact]\ngroup = \"c\"\n");
    expect_err(&text, "contact.obstacle", "[contact]");
}

#[test]
fn reject_missing_section() {
    let text = MINIMAL.replace("[mesh]\nfile = \"meshes/plate.msh\"\n", "");
    let e = parse(&text).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("mesh"), "{e}");
    assert!(e.message.contains("[mesh]"), "{e}");
}

#[test]
fn reject_non_positive_young() {
    for bad in ["0.0", "-1", "-0.5e3"] {
        let e = expect_err(
            &replace(MINIMAL, "young = 2.0", &format!("young = {bad}")),
            "material.young",
            "young",
        );
        assert!(e.message.contains("> 0"), "{e}");
    }
}

#[test]
fn reject_poisson_out_of_range() {
    for bad in ["0.5", "-1", "0.7", "-3.0", "nan"] {
        expect_err(
            &replace(MINIMAL, "poisson = 0.3", &format!("poisson = {bad}")),
            "material.poisson",
            "poisson",
        );
    }
    for good in ["0.49", "-0.99", "0"] {
        assert!(parse(&replace(
            MINIMAL,
            "poisson = 0.3",
            &format!("poisson = {good}")
        ))
        .is_ok());
    }
}

#[test]
fn reject_unknown_model() {
    let e = expect_err(
        &replace(MINIMAL, "plane_strain", "axisymmetric"),
        "material.model",
        "model",
    );
    assert!(e.message.contains("plane_stress"), "{e}");
}

#[test]
fn reject_pressure_and_traction_both() {
    let text = with("[[neumann]]\ngroup = \"l\"\npressure = 1.0\ntraction = [0, 1]\n");
    let e = expect_err(&text, "neumann[0]", "pressure");
    assert!(e.message.contains("exactly one"), "{e}");
}

#[test]
fn reject_pressure_and_traction_neither() {
    let text = with("[[neumann]]\ngroup = \"a\"\npressure = 1\n\n[[neumann]]\ngroup = \"l\"\n");
    let e = parse(&text).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("neumann[1]"), "{e}");
    // The second [[neumann]] header.
    let second = text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "[[neumann]]")
        .nth(1)
        .unwrap()
        .0
        + 1;
    assert_eq!(e.line, Some(second), "{e}");
}

#[test]
fn reject_bad_vectors() {
    let text = with("[[dirichlet]]\ngroup = \"a\"\nvalue = [0, 0]\n\n[[dirichlet]]\ngroup = \"b\"\nvalue = [0, 0, 0, 0]\n");
    let e = expect_err(&text, "dirichlet[1].value", "[0, 0, 0, 0]");
    assert!(e.message.contains("2 or 3"), "{e}");
    expect_err(
        &with("[[dirichlet]]\ngroup = \"a\"\nvalue = [0, \"fixed\"]\n"),
        "dirichlet[0].value[1]",
        "fixed",
    );
    expect_err(
        &with("[[dirichlet]]\ngroup = \"a\"\nvalue = [0, true]\n"),
        "dirichlet[0].value[1]",
        "true",
    );
    expect_err(
        &with("[body_force]\nvalue = [0, \"x\"]\n"),
        "body_force.value[1]",
        "value",
    );
    expect_err(
        &with("[body_force]\nvalue = [1]\n"),
        "body_force.value",
        "value",
    );
    expect_err(
        &with("[body_force]\nvalue = [0, inf]\n"),
        "body_force.value[1]",
        "value",
    );
    expect_err(
        &with("[[neumann]]\ngroup = \"l\"\ntraction = 1.0\n"),
        "neumann[0].traction",
        "traction",
    );
    expect_err(
        &with("[[dirichlet]]\ngroup = \"\"\nvalue = [0, 0]\n"),
        "dirichlet[0].group",
        "group",
    );
}

#[test]
fn reject_unknown_field() {
    let e = expect_err(
        &with("[output]\nfields = [\"displacement\", \"strain\"]\n"),
        "output.fields[1]",
        "fields",
    );
    assert!(e.message.contains("von_mises_thesis"), "{e}");
}

#[test]
fn solver_reuse_values_and_rejection() {
    for (name, want) in [
        ("auto", Reuse::Auto),
        ("never", Reuse::Never),
        ("always", Reuse::Always),
    ] {
        let c = parse(&with(&format!("[solver]\nreuse = \"{name}\"\n"))).unwrap();
        assert_eq!(c.solver.reuse, want);
        assert_eq!(want.name(), name);
    }
    let c = parse_set(MINIMAL, &["solver.reuse=\"never\""]).unwrap();
    assert_eq!(c.solver.reuse, Reuse::Never);
    let e = expect_err(
        &with("[solver]\npreset = \"direct\"\nreuse = \"sometimes\"\n"),
        "solver.reuse",
        "reuse",
    );
    assert!(e.message.contains("\"auto\", \"never\", \"always\""), "{e}");
    expect_err(&with("[solver]\nreuse = true\n"), "solver.reuse", "reuse");
}

#[test]
fn solver_repeatable_is_a_boolean_off_by_default() {
    assert!(!parse(MINIMAL).unwrap().solver.repeatable);
    let c = parse(&with("[solver]\nrepeatable = true\n")).unwrap();
    assert!(c.solver.repeatable);
    let c = parse_set(MINIMAL, &["solver.repeatable=true"]).unwrap();
    assert!(c.solver.repeatable);
    let e = expect_err(
        &with("[solver]\nrepeatable = \"yes\"\n"),
        "solver.repeatable",
        "repeatable",
    );
    assert!(e.message.contains("boolean"), "{e}");
}

#[test]
fn solver_dense_threads_is_auto_or_a_count() {
    assert_eq!(
        parse(MINIMAL).unwrap().solver.dense_threads,
        DenseThreads::Auto
    );
    let c = parse(&with("[solver]\ndense_threads = 2\n")).unwrap();
    assert_eq!(c.solver.dense_threads, DenseThreads::Fixed(2));
    let c = parse_set(MINIMAL, &["solver.dense_threads=\"auto\""]).unwrap();
    assert_eq!(c.solver.dense_threads, DenseThreads::Auto);
    for bad in ["0", "-1", "2000", "\"all\"", "1.5"] {
        expect_err(
            &with(&format!("[solver]\ndense_threads = {bad}\n")),
            "solver.dense_threads",
            "dense_threads",
        );
    }
}

#[test]
fn reject_unknown_preset() {
    let e = expect_err(
        &with("[solver]\npreset = \"lu\"\n"),
        "solver.preset",
        "preset",
    );
    assert!(e.message.contains("\"direct\", \"iterative\""), "{e}");
    expect_err(&with("[solver]\nrtol = 0\n"), "solver.rtol", "rtol");
    expect_err(&with("[solver]\nrtol = 2\n"), "solver.rtol", "rtol");
}

#[test]
fn reject_unknown_obstacle_type() {
    let text = with("[contact]\ngroup = \"c\"\nobstacle = { type = \"torus\", point = [0, 0] }\n");
    let e = expect_err(&text, "contact.obstacle.type", "obstacle");
    assert!(
        e.message
            .contains("\"plane\", \"sphere\", \"cylinder\", \"cone\", \"pyramid\", \"punch\""),
        "{e}"
    );
}

#[test]
fn reject_bad_obstacles() {
    let c = "[contact]\ngroup = \"c\"\n";
    expect_err(
        &with(&format!(
            "{c}obstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 0] }}\n"
        )),
        "contact.obstacle.normal",
        "obstacle",
    );
    expect_err(
        &with(&format!(
            "{c}obstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 0, 1] }}\n"
        )),
        "contact.obstacle.normal",
        "obstacle",
    );
    expect_err(
        &with(&format!(
            "{c}obstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1], radius = 1 }}\n"
        )),
        "contact.obstacle.radius",
        "obstacle",
    );
    expect_err(
        &with(&format!(
            "{c}[contact.obstacle]\ntype = \"sphere\"\ncenter = [0, 0]\nradius = 0\n"
        )),
        "contact.obstacle.radius",
        "radius",
    );
    expect_err(
        &with(&format!(
            "{c}[contact.obstacle]\ncenter = [0, 0]\nradius = 1\n"
        )),
        "contact.obstacle.type",
        "[contact.obstacle]",
    );
    expect_err(
        &with(&format!("{c}obstacle = \"plane\"\n")),
        "contact.obstacle",
        "obstacle",
    );
}

#[test]
fn reject_negative_threshold() {
    let text = with(
        "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n\
         friction = { law = \"tresca\", threshold = -0.1 }\n",
    );
    let e = expect_err(&text, "contact.friction.threshold", "friction");
    assert!(e.message.contains(">= 0"), "{e}");
}

#[test]
fn coulomb_friction_key() {
    let c = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n";
    let parse = |f: &str| {
        parse(&with(&format!("{c}friction = {f}\n")))
            .expect("valid")
            .contacts
            .swap_remove(0)
            .friction
    };
    assert_eq!(
        parse("{ law = \"coulomb\", mu = 0.3 }"),
        Friction::Coulomb {
            mu: 0.3,
            algorithm: CoulombAlgorithm::Newton
        }
    );
    assert_eq!(
        parse("{ law = \"coulomb\", mu = 0, algorithm = \"fixed-point\" }"),
        Friction::Coulomb {
            mu: 0.0,
            algorithm: CoulombAlgorithm::FixedPoint
        }
    );
    assert_eq!(
        parse("{ law = \"coulomb\", mu = 1, algorithm = \"newton\" }"),
        Friction::Coulomb {
            mu: 1.0,
            algorithm: CoulombAlgorithm::Newton
        }
    );
    let e = expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"coulomb\", mu = -0.1 }}\n"
        )),
        "contact.friction.mu",
        "friction",
    );
    assert!(e.message.contains(">= 0"), "{e}");
    expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"coulomb\", mu = nan }}\n"
        )),
        "contact.friction.mu",
        "friction",
    );
    expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"coulomb\", mu = inf }}\n"
        )),
        "contact.friction.mu",
        "friction",
    );
    expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"coulomb\", mu = \"0.3\" }}\n"
        )),
        "contact.friction.mu",
        "friction",
    );
    expect_err(
        &with(&format!("{c}friction = {{ law = \"coulomb\" }}\n")),
        "contact.friction.mu",
        "friction",
    );
    let e = expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"coulomb\", mu = 0.3, algorithm = \"picard\" }}\n"
        )),
        "contact.friction.algorithm",
        "friction",
    );
    assert!(e.message.contains("fixed-point"), "{e}");
    expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"tresca\", threshold = 1, algorithm = \"newton\" }}\n"
        )),
        "contact.friction.algorithm",
        "friction",
    );
}

#[test]
fn reject_bad_friction_and_rigid_modes() {
    let c = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n";
    expect_err(
        &with(&format!("{c}friction = \"tresca\"\n")),
        "contact.friction",
        "friction",
    );
    expect_err(
        &with(&format!("{c}friction = \"coulomb\"\n")),
        "contact.friction",
        "friction",
    );
    expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"coulomb\", threshold = 1 }}\n"
        )),
        "contact.friction.threshold",
        "friction",
    );
    expect_err(
        &with(&format!("{c}friction = {{ law = \"tresca\" }}\n")),
        "contact.friction.threshold",
        "friction",
    );
    expect_err(
        &with(&format!(
            "{c}friction = {{ law = \"tresca\", threshold = 1, mu = 0.3 }}\n"
        )),
        "contact.friction.mu",
        "friction",
    );
    expect_err(
        &with(&format!("{c}rigid_modes = \"yes\"\n")),
        "contact.rigid_modes",
        "rigid",
    );
}

#[test]
fn reject_non_positive_c() {
    for bad in ["0", "-1.0"] {
        let e = expect_err(&with(&format!("[newton]\nc = {bad}\n")), "newton.c", "c =");
        assert!(e.message.contains("> 0"), "{e}");
    }
}

#[test]
fn reject_bad_newton_settings() {
    expect_err(
        &with("[newton]\nmax_steps = 0\n"),
        "newton.max_steps",
        "max_steps",
    );
    expect_err(
        &with("[newton]\nmax_steps = -4\n"),
        "newton.max_steps",
        "max_steps",
    );
    expect_err(&with("[newton]\ntol_u = 0.0\n"), "newton.tol_u", "tol_u");
    expect_err(&with("[newton]\nstrict = 1\n"), "newton.strict", "strict");
    expect_err(
        &with("[newton]\nstrict = \"yes\"\n"),
        "newton.strict",
        "strict",
    );
    assert!(
        parse(&with("[newton]\nstrict = true\n"))
            .unwrap()
            .newton
            .strict
    );
    assert!(
        parse_set(MINIMAL, &["newton.strict=true"])
            .unwrap()
            .newton
            .strict
    );
    let e = expect_err(
        &with("[newton]\ninit = \"active\"\n"),
        "newton.init",
        "init",
    );
    assert!(e.message.contains("all_active"), "{e}");
}

#[test]
fn missing_case_file_is_input_error() {
    let p = Path::new("/nonexistent/dir/case.toml");
    let e = Case::load(p, &[], None).unwrap_err();
    assert_eq!(e.file, p);
    assert!(e.message.contains("cannot read"), "{e}");
}

#[test]
fn load_from_disk_resolves_paths() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("beam.toml");
    std::fs::write(&path, MINIMAL).unwrap();
    // the mesh file must be there: the case file's error, with its key and line
    let e = Case::load(&path, &[], None).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("mesh.file"), "{e:?}");
    assert!(e.line.is_some() && e.message.contains("plate.msh"), "{e:?}");
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/plate.msh"), "").unwrap();
    let c = Case::load(&path, &[], None).unwrap();
    assert_eq!(c.mesh.file, dir.path().join("meshes/plate.msh"));
    assert_eq!(c.output.dir, Path::new("out/beam"));
    let c = Case::load(&path, &[], Some(Path::new("elsewhere"))).unwrap();
    assert_eq!(c.output.dir, Path::new("elsewhere"));
}

#[test]
fn overrides_apply() {
    let c = parse_set(
        FULL,
        &[
            "mesh.file=fine.msh",
            "newton.c=25",
            "output.fields=[\"displacement\"]",
            "dirichlet.0.group=clamp2",
            "dirichlet.1.value.0 = 0.1",
            "material.model = \"plane_strain\"",
            "contact.obstacle.normal=[0, -1]",
            "solver.petsc_options=-pc_type lu -ksp_type preonly",
        ],
    )
    .unwrap();
    assert_eq!(c.mesh.file, Path::new("/cases/fine.msh"));
    assert_eq!(c.newton.c, Some(25.0));
    assert_eq!(c.newton.max_steps, 7, "other keys untouched");
    assert_eq!(c.output.fields, vec![OutputField::Displacement]);
    assert_eq!(c.dirichlet[0].group, "clamp2");
    assert_eq!(c.dirichlet[1].value, vec![Some(0.1), Some(-0.5)]);
    assert_eq!(c.materials[0].model, Some(MaterialModel::PlaneStrain));
    match &c.contacts.first().unwrap().obstacle {
        ObstacleSpec::Plane { normal, .. } => assert_eq!(normal, &vec![0.0, -1.0]),
        o => panic!("{o:?}"),
    }
    assert_eq!(c.solver.petsc_options, "-pc_type lu -ksp_type preonly");
    // A key set from the command line has no line.
    assert_eq!(c.line_of("newton.c"), None);
    assert_eq!(c.line_of("newton.max_steps"), Some(line(FULL, "max_steps")));
}

/// The messages' form of an entry's key, `dirichlet[1].value`, is a `--set` key too.
#[test]
fn overrides_take_the_bracketed_index_of_the_messages() {
    let c = parse_set(
        FULL,
        &["dirichlet[0].group=clamp2", "dirichlet[1].value[0] = 0.1"],
    )
    .unwrap();
    assert_eq!(c.dirichlet[0].group, "clamp2");
    assert_eq!(c.dirichlet[1].value, vec![Some(0.1), Some(-0.5)]);
    assert!(parse_set(FULL, &["dirichlet[x].group=a"]).is_err());
}

#[test]
fn overrides_create_sections_and_entries() {
    let c = parse_set(
        MINIMAL,
        &[
            "newton.c=10",
            "newton.init=all_active",
            "dirichlet.0.group=clamp",
            "dirichlet.0.value=[0, \"free\"]",
            "contact.group=c",
            "contact.obstacle={type=\"sphere\", center=[0, 2], radius=1}",
        ],
    )
    .unwrap();
    assert_eq!(c.newton.c, Some(10.0));
    assert_eq!(c.newton.init, NewtonInit::AllActive);
    assert_eq!(
        c.dirichlet,
        vec![Dirichlet {
            group: "clamp".into(),
            value: vec![Some(0.0), None],
            ramp: true,
        }]
    );
    assert_eq!(
        c.contacts.into_iter().next().unwrap().obstacle,
        ObstacleSpec::Sphere {
            center: vec![0.0, 2.0],
            radius: 1.0
        }
    );
    let o = Case::parse(
        MINIMAL,
        Path::new(FILE),
        &["output.dir=a/b".to_string()],
        Some(Path::new("c/d")),
    )
    .unwrap();
    assert_eq!(o.output.dir, Path::new("c/d"), "-o wins over output.dir");
}

#[test]
fn override_unknown_key_rejected() {
    let e = parse_set(MINIMAL, &["newton.cc=10"]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("newton.cc"), "{e}");
    assert_eq!(e.line, None);
    assert!(e.message.contains("(from --set)"), "{e}");
    assert!(e.message.contains("init, c, max_steps, tol_u"), "{e}");
}

#[test]
fn override_type_mismatch_rejected() {
    let e = parse_set(MINIMAL, &["newton.max_steps=many"]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("newton.max_steps"), "{e}");
    assert!(
        e.message.contains("integer") && e.message.contains("string"),
        "{e}"
    );
    assert!(e.message.contains("(from --set)"), "{e}");
    let e = parse_set(MINIMAL, &["material.young=-3"]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material.young"), "{e}");
    assert!(e.to_string().contains("(from --set)"), "{e}");
}

#[test]
fn malformed_overrides_rejected() {
    for (spec, key) in [
        ("newton.c", "newton.c"),
        ("newton..c=1", "newton..c"),
        ("mesh.file.x=1", "mesh.file"),
        ("dirichlet.3.group=x", "dirichlet[3]"),
        ("dirichlet.first.group=x", "dirichlet"),
    ] {
        let e = parse_set(FULL, &[spec]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some(key), "{spec}: {e}");
        assert!(e.message.contains("(from --set)"), "{e}");
        assert_eq!(e.line, None);
    }
}

fn groups(list: &[(&str, usize)]) -> Vec<(String, usize)> {
    list.iter().map(|(n, d)| (n.to_string(), *d)).collect()
}

#[test]
fn check_against_mesh_accepts_matching_mesh() {
    let c = parse(FULL).unwrap();
    let g = groups(&[
        ("clamp", 1),
        ("roller", 0),
        ("load", 1),
        ("side", 1),
        ("contact", 1),
        ("body", 2),
    ]);
    c.check_against_mesh(2, &g).unwrap();
}

/// A body pair's master group given as a volume group: named as such, not as "no facets".
#[test]
fn check_against_mesh_refuses_a_volume_as_a_body_pairs_master() {
    let text = FULL.replace(
        r#"obstacle = { type = "plane", point = [0.0, -1.0], normal = [3.0, 4.0] }"#,
        r#"obstacle = { type = "body", group = "body" }"#,
    );
    assert_ne!(text, FULL);
    let c = parse(&text).unwrap();
    let g = groups(&[
        ("clamp", 1),
        ("roller", 0),
        ("load", 1),
        ("side", 1),
        ("contact", 1),
        ("body", 2),
    ]);
    let e = c.check_against_mesh(2, &g).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.obstacle.group"), "{e}");
    assert!(e.message.contains("boundary group (dimension 1)"), "{e}");
}

#[test]
fn check_against_mesh_unknown_group_lists_names() {
    let c = parse(FULL).unwrap();
    let g = groups(&[
        ("clamp", 1),
        ("load", 1),
        ("side", 1),
        ("contact", 1),
        ("body", 2),
    ]);
    let e = c.check_against_mesh(2, &g).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("dirichlet[1].group"), "{e}");
    assert_eq!(e.line, Some(line(FULL, "\"roller\"")));
    for name in [
        "\"clamp\"",
        "\"load\"",
        "\"side\"",
        "\"contact\"",
        "\"body\"",
    ] {
        assert!(e.message.contains(name), "{e}");
    }
    let e = c.check_against_mesh(2, &[]).unwrap_err();
    assert!(e.message.contains("no named physical groups"), "{e}");
}

#[test]
fn check_against_mesh_needs_boundary_groups() {
    let c = parse(FULL).unwrap();
    let g = groups(&[
        ("clamp", 1),
        ("roller", 0),
        ("load", 1),
        ("side", 2),
        ("contact", 1),
    ]);
    let e = c.check_against_mesh(2, &g).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("neumann[1].group"), "{e}");
    assert!(e.message.contains("boundary"), "{e}");
    let g = groups(&[
        ("clamp", 1),
        ("roller", 0),
        ("load", 1),
        ("side", 1),
        ("contact", 0),
    ]);
    let e = c.check_against_mesh(2, &g).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.group"), "{e}");
    assert_eq!(e.line, Some(line(FULL, "group = \"contact\"")));
}

#[test]
fn check_against_mesh_wrong_vector_length() {
    // 3D case (model omitted) with a 2-component Dirichlet value.
    let text = replace(MINIMAL, "model = \"plane_strain\"\n", "")
        + "[[dirichlet]]\ngroup = \"clamp\"\nvalue = [0, 0]\n";
    let c = parse(&text).unwrap();
    let g = groups(&[("clamp", 2)]);
    let e = c.check_against_mesh(3, &g).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("dirichlet[0].value"), "{e}");
    assert_eq!(e.line, Some(line(&text, "value = [0, 0]")));
    // Obstacle and body force lengths, in 2D.
    let c = parse(&with("[body_force]\nvalue = [0, 0, 1]\n")).unwrap();
    let e = c.check_against_mesh(2, &[]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("body_force.value"), "{e}");
    let c = parse(&with(
        "[contact]\ngroup = \"c\"\nobstacle = { type = \"sphere\", center = [0, 0, 1], radius = 1 }\n",
    ))
    .unwrap();
    let e = c.check_against_mesh(2, &groups(&[("c", 1)])).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.obstacle.center"), "{e}");
    let c = parse(&with("[[neumann]]\ngroup = \"l\"\ntraction = [0, 0, 1]\n")).unwrap();
    let e = c.check_against_mesh(2, &groups(&[("l", 1)])).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("neumann[0].traction"), "{e}");
}

#[test]
fn model_against_dimension() {
    let c = parse(MINIMAL).unwrap();
    assert_eq!(c.model(2).unwrap(), MaterialModel::PlaneStrain);
    let e = c.check_against_mesh(3, &[]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material.model"), "{e}");
    assert_eq!(e.line, Some(line(MINIMAL, "model")));
    let e = c.model(1).unwrap_err();
    assert!(e.message.contains("dimension 1"), "{e}");

    let no_model = replace(MINIMAL, "model = \"plane_strain\"\n", "");
    let c = parse(&no_model).unwrap();
    assert_eq!(c.model(3).unwrap(), MaterialModel::ThreeD);
    let e = c.check_against_mesh(2, &[]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material"), "{e}");
    assert_eq!(e.line, Some(line(&no_model, "[material]")));
    assert!(e.message.contains("plane_strain"), "{e}");

    let three = replace(MINIMAL, "plane_strain", "3d");
    let c = parse(&three).unwrap();
    assert_eq!(c.model(3).unwrap(), MaterialModel::ThreeD);
    let e = c.model(2).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material.model"), "{e}");
    assert!(e.message.contains("2D"), "{e}");
}

#[test]
fn override_unquoted_array_hint() {
    let e = parse_set(MINIMAL, &["output.fields=[displacement]"]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("output.fields"), "{e}");
    assert!(e.message.contains("quote"), "{e}");
}

// ---- sizes bounded -----------------------------------------------------------------

#[test]
fn reject_huge_case_file_before_building_its_tree() {
    // 3 million array entries used to cost ~700 MB and 10 s before the unknown key was found.
    let text = format!("{MINIMAL}junk = [{}]\n", "1,".repeat(3_000_000));
    let e = parse(&text).unwrap_err();
    assert!(e.message.contains("larger than 256 KiB"), "{e}");
    // The same through the file reader.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.toml");
    std::fs::write(&p, &text).unwrap();
    let e = Case::load(&p, &[], None).unwrap_err();
    assert_eq!(e.file, p);
    assert!(e.message.contains("larger than 256 KiB"), "{e}");
    // Just under the bound (a long comment) is read.
    let ok = format!(
        "{MINIMAL}#{}\n",
        "x".repeat(MAX_CASE_BYTES - MINIMAL.len() - 2)
    );
    assert!(ok.len() <= MAX_CASE_BYTES);
    parse(&ok).unwrap();
}

#[test]
fn reject_deep_set_key_path_without_overflowing_the_stack() {
    // A 60 000-component key path used to overflow the stack (SIGSEGV) while the tree of
    // nested tables was walked and dropped.
    for unit in ["a.", "0."] {
        let spec = format!("x.{}b=1", unit.repeat(60_000));
        let e = parse_set(MINIMAL, &[&spec]).unwrap_err();
        assert!(e.message.contains("key path has 60002 components"), "{e}");
    }
    // A path of the schema's depth is applied (and then validated as usual).
    let e = parse_set(MINIMAL, &["contact.obstacle.point=[0.0, 0.0]"]).unwrap_err();
    assert!(!e.message.contains("key path has"), "{e}");
    assert!(e.key.as_deref().unwrap_or("").starts_with("contact"), "{e}");
}

#[test]
fn deep_nesting_in_the_file_is_a_syntax_error() {
    for text in [
        format!(
            "{MINIMAL}x = {}{}\n",
            "[".repeat(10_000),
            "]".repeat(10_000)
        ),
        format!("{MINIMAL}x{} = 1\n", ".a".repeat(10_000)),
        format!("{MINIMAL}[{}a]\n", "a.".repeat(10_000)),
    ] {
        let e = parse(&text).unwrap_err();
        assert!(e.message.contains("recursion limit"), "{e}");
    }
}

#[test]
fn load_section() {
    assert_eq!(parse(MINIMAL).unwrap().load, None);
    let c = parse(&with("[load]\nsteps = 4\n")).unwrap();
    assert_eq!(
        c.load,
        Some(LoadSection {
            factors: vec![0.25, 0.5, 0.75, 1.0],
            max_cutbacks: load::DEFAULT_MAX_CUTBACKS,
        })
    );
    let c = parse(&with(
        "[load]\nfactors = [0.5, 2, 0.25]\nmax_cutbacks = 0\n",
    ))
    .unwrap();
    assert_eq!(
        c.load,
        Some(LoadSection {
            factors: vec![0.5, 2.0, 0.25],
            max_cutbacks: 0,
        })
    );
    let c = parse_set(MINIMAL, &["load.steps=3"]).unwrap();
    assert_eq!(c.load.unwrap().factors.len(), 3);
}

#[test]
fn load_rejections() {
    for (extra, key, needle, says) in [
        (
            "[load]\nmax_cutbacks = 2\n",
            "load",
            "[load]",
            "one of 'steps'",
        ),
        (
            "[load]\nsteps = 2\nfactors = [1.0]\n",
            "load.factors",
            "factors",
            "not both",
        ),
        ("[load]\nsteps = 0\n", "load.steps", "steps", "from 1"),
        ("[load]\nsteps = 2.5\n", "load.steps", "steps", "integer"),
        (
            "[load]\nfactors = []\n",
            "load.factors",
            "factors",
            "at least one",
        ),
        (
            "[load]\nfactors = 1.0\n",
            "load.factors",
            "factors",
            "array",
        ),
        (
            "[load]\nfactors = [0.5, -1]\n",
            "load.factors[1]",
            "factors",
            "≥ 0",
        ),
        (
            "[load]\nfactors = [0.5, nan]\n",
            "load.factors[1]",
            "factors",
            "finite",
        ),
        (
            "[load]\nfactors = [0.5, \"x\"]\n",
            "load.factors[1]",
            "factors",
            "number",
        ),
        (
            "[load]\nfactors = [0.5, 0.5]\n",
            "load.factors[1]",
            "factors",
            "equals",
        ),
        (
            "[load]\nsteps = 2\nmax_cutbacks = -1\n",
            "load.max_cutbacks",
            "max_cutbacks",
            "from 0",
        ),
        (
            "[load]\nsteps = 2\nmax_cutbacks = 31\n",
            "load.max_cutbacks",
            "max_cutbacks",
            "to 30",
        ),
        (
            "[load]\nsteps = 2\ncutbacks = 3\n",
            "load.cutbacks",
            "cutbacks",
            "allowed keys",
        ),
    ] {
        let text = with(extra);
        let e = expect_err(&text, key, needle);
        assert!(e.message.contains(says), "{extra}: {e}");
    }
    let text = format!("load = 3\n{MINIMAL}");
    assert!(expect_err(&text, "load", "load = 3")
        .message
        .contains("table"));
}

#[test]
fn mesh_refine_and_project() {
    let c = parse(MINIMAL).unwrap();
    assert_eq!((c.mesh.refine, c.mesh.project.len()), (0, 0));
    let text = replace(
        MINIMAL,
        "file = \"meshes/plate.msh\"\n",
        "file = \"meshes/plate.msh\"\nrefine = 2\n\n[[mesh.project]]\ngroup = \"arc\"\n\
         shape = { type = \"sphere\", center = [0, 1], radius = 1 }\n\n[[mesh.project]]\n\
         group = \"flat\"\nshape = { type = \"plane\", point = [0, 0], normal = [0, 2] }\n",
    );
    let c = parse(&text).unwrap();
    assert_eq!(c.mesh.refine, 2);
    assert_eq!(
        c.mesh.project,
        vec![
            Projection {
                group: "arc".into(),
                shape: ObstacleSpec::Sphere {
                    center: vec![0.0, 1.0],
                    radius: 1.0
                }
            },
            Projection {
                group: "flat".into(),
                shape: ObstacleSpec::Plane {
                    point: vec![0.0, 0.0],
                    normal: vec![0.0, 1.0]
                }
            }
        ]
    );
    let groups = |v: &[(&str, usize)]| -> Vec<(String, usize)> {
        v.iter().map(|(n, d)| (n.to_string(), *d)).collect()
    };
    c.check_projections(2, &groups(&[("arc", 1), ("flat", 1), ("body", 2)]))
        .unwrap();
    let e = c
        .check_projections(2, &groups(&[("arc", 1), ("body", 2)]))
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("mesh.project[1].group"), "{e}");
    assert_eq!(e.line, Some(line(&text, "group = \"flat\"")), "{e}");
    let e = c
        .check_projections(2, &groups(&[("arc", 2), ("flat", 1)]))
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("mesh.project[0].group"), "{e}");
    let e = c
        .check_projections(3, &groups(&[("arc", 2), ("flat", 2)]))
        .unwrap_err();
    assert_eq!(
        e.key.as_deref(),
        Some("mesh.project[0].shape.center"),
        "{e}"
    );
    for bad in ["-1", "1.5", "\"1\"", "11"] {
        expect_err(
            &replace(&text, "refine = 2", &format!("refine = {bad}")),
            "mesh.refine",
            "refine =",
        );
    }
    expect_err(
        &replace(&text, "group = \"arc\"", "group = \"arc\"\ncolor = 1"),
        "mesh.project[0].color",
        "color",
    );
    expect_err(
        &replace(&text, "type = \"plane\"", "type = \"torus\""),
        "mesh.project[1].shape.type",
        "torus",
    );
}

// ---- the indenter obstacles: cylinder, cone, pyramid, punch --------------------------------

const CYLINDER: &str = "type = \"cylinder\"\npoint = [0, 0, 1.5]\naxis = [0, 3, 0]\nradius = 0.5\n";
const CONE: &str = "type = \"cone\"\napex = [0, 0.99]\naxis = [0, 2]\nhalf_angle = 70\n";
const PYRAMID: &str = "type = \"pyramid\"\napex = [0, 0, 0.49]\naxis = [0, 0, 1]\n\
                       half_angle = 68\nfaces = 4\nazimuth = 45\n";
const PUNCH: &str = "type = \"punch\"\ncenter = [0, 0, 0.49]\naxis = [0, 0, 0.5]\n\
                     radius = 0.3\nedge_radius = 0.05\n";

/// `base` with a contact section whose obstacle is the table `[contact.obstacle]` of `lines`.
fn obstacle_case(base: &str, lines: &str) -> String {
    format!("{base}\n[contact]\ngroup = \"c\"\n\n[contact.obstacle]\n{lines}")
}

fn minimal_3d() -> String {
    replace(MINIMAL, "model = \"plane_strain\"\n", "")
}

fn spec(lines: &str) -> ObstacleSpec {
    parse(&obstacle_case(MINIMAL, lines))
        .unwrap()
        .contacts
        .swap_remove(0)
        .obstacle
}

#[test]
fn indenter_obstacles_parse() {
    assert_eq!(
        spec(CYLINDER),
        ObstacleSpec::Cylinder {
            point: vec![0.0, 0.0, 1.5],
            axis: vec![0.0, 1.0, 0.0],
            radius: 0.5
        }
    );
    assert_eq!(
        spec(CONE),
        ObstacleSpec::Cone {
            apex: vec![0.0, 0.99],
            axis: vec![0.0, 1.0],
            half_angle: 70.0
        }
    );
    assert_eq!(
        spec(PYRAMID),
        ObstacleSpec::Pyramid {
            apex: vec![0.0, 0.0, 0.49],
            axis: vec![0.0, 0.0, 1.0],
            half_angle: 68.0,
            faces: 4,
            azimuth: 45.0
        }
    );
    assert_eq!(
        spec(PUNCH),
        ObstacleSpec::Punch {
            center: vec![0.0, 0.0, 0.49],
            axis: vec![0.0, 0.0, 1.0],
            radius: 0.3,
            edge_radius: 0.05
        }
    );
    // Optional keys: azimuth 0, edge_radius 0 (a sharp edge); edge_radius = radius is allowed.
    match spec(&replace(PYRAMID, "azimuth = 45\n", "")) {
        ObstacleSpec::Pyramid { azimuth, .. } => assert_eq!(azimuth, 0.0),
        o => panic!("{o:?}"),
    }
    match spec(&replace(PUNCH, "edge_radius = 0.05\n", "")) {
        ObstacleSpec::Punch { edge_radius, .. } => assert_eq!(edge_radius, 0.0),
        o => panic!("{o:?}"),
    }
    match spec(&replace(PUNCH, "edge_radius = 0.05", "edge_radius = 0.3")) {
        ObstacleSpec::Punch { edge_radius, .. } => assert_eq!(edge_radius, 0.3),
        o => panic!("{o:?}"),
    }
    // A huge axis is normalised without overflowing; the inline table form; --set.
    match spec(&replace(CONE, "axis = [0, 2]", "axis = [1e300, 1e300]")) {
        ObstacleSpec::Cone { axis, .. } => {
            let s = 0.5f64.sqrt();
            assert!((axis[0] - s).abs() < 1e-15 && (axis[1] - s).abs() < 1e-15);
        }
        o => panic!("{o:?}"),
    }
    let c = parse(&with(
        "[contact]\ngroup = \"c\"\n\
         obstacle = { type = \"cone\", apex = [0, 1], axis = [0, 1], half_angle = 45 }\n",
    ))
    .unwrap();
    assert!(matches!(
        c.contacts.into_iter().next().unwrap().obstacle,
        ObstacleSpec::Cone { half_angle, .. } if half_angle == 45.0
    ));
    let c = parse_set(
        &obstacle_case(MINIMAL, CONE),
        &["contact.obstacle.half_angle=30"],
    )
    .unwrap();
    assert!(matches!(
        c.contacts.into_iter().next().unwrap().obstacle,
        ObstacleSpec::Cone { half_angle, .. } if half_angle == 30.0
    ));
    let e = parse_set(
        &obstacle_case(MINIMAL, CONE),
        &["contact.obstacle.half_angle=90"],
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.obstacle.half_angle"), "{e}");
    assert!(e.message.contains("(from --set)"), "{e}");
}

/// Rejects `shape` with `from` replaced by `to`: the key `contact.obstacle.<key>` at its line
/// (at the `[contact.obstacle]` line when the key is missing), the message containing `msg`.
fn reject_shape(shape: &str, from: &str, to: &str, key: &str, msg: &str) {
    let text = obstacle_case(MINIMAL, &replace(shape, from, to));
    let needle = if to.is_empty() {
        "[contact.obstacle]"
    } else {
        key.split('[').next().unwrap()
    };
    let e = expect_err(&text, &format!("contact.obstacle.{key}"), needle);
    assert!(e.message.contains(msg), "{from} -> {to}: {e}");
}

#[test]
fn reject_bad_cylinder_obstacles() {
    reject_shape(
        CYLINDER,
        "point = [0, 0, 1.5]\n",
        "",
        "point",
        "missing required key",
    );
    reject_shape(
        CYLINDER,
        "axis = [0, 3, 0]\n",
        "",
        "axis",
        "missing required key",
    );
    reject_shape(
        CYLINDER,
        "radius = 0.5\n",
        "",
        "radius",
        "missing required key",
    );
    reject_shape(
        CYLINDER,
        "axis = [0, 3, 0]",
        "axis = [0, 0, 0]",
        "axis",
        "the axis must be a nonzero vector",
    );
    reject_shape(
        CYLINDER,
        "axis = [0, 3, 0]",
        "axis = [0, 3]",
        "axis",
        "has 2 components but point has 3",
    );
    reject_shape(
        CYLINDER,
        "axis = [0, 3, 0]",
        "axis = [0, 3, 0, 1]",
        "axis",
        "expected 2 or 3 components",
    );
    reject_shape(
        CYLINDER,
        "axis = [0, 3, 0]",
        "axis = [0, \"y\", 0]",
        "axis[1]",
        "expected a number",
    );
    reject_shape(
        CYLINDER,
        "axis = [0, 3, 0]",
        "axis = 1",
        "axis",
        "expected an array of numbers",
    );
    reject_shape(
        CYLINDER,
        "radius = 0.5",
        "radius = 0",
        "radius",
        "must be > 0, got 0",
    );
    reject_shape(
        CYLINDER,
        "radius = 0.5",
        "radius = -2",
        "radius",
        "must be > 0, got -2",
    );
    reject_shape(
        CYLINDER,
        "radius = 0.5",
        "radius = 0.5\nhalf_angle = 30",
        "half_angle",
        "unknown key in [contact.obstacle]; allowed keys: type, point, axis, radius",
    );
}

#[test]
fn reject_bad_cone_obstacles() {
    reject_shape(
        CONE,
        "apex = [0, 0.99]\n",
        "",
        "apex",
        "missing required key",
    );
    reject_shape(
        CONE,
        "half_angle = 70\n",
        "",
        "half_angle",
        "missing required key",
    );
    reject_shape(
        CONE,
        "half_angle = 70",
        "half_angle = 0",
        "half_angle",
        "must be in (0, 90) degrees, got 0",
    );
    reject_shape(
        CONE,
        "half_angle = 70",
        "half_angle = 90",
        "half_angle",
        "must be in (0, 90) degrees, got 90",
    );
    reject_shape(
        CONE,
        "half_angle = 70",
        "half_angle = -10",
        "half_angle",
        "must be in (0, 90) degrees, got -10",
    );
    reject_shape(
        CONE,
        "half_angle = 70",
        "half_angle = 120.5",
        "half_angle",
        "must be in (0, 90) degrees, got 120.5",
    );
    reject_shape(
        CONE,
        "half_angle = 70",
        "half_angle = \"70\"",
        "half_angle",
        "expected a number",
    );
    reject_shape(
        CONE,
        "half_angle = 70",
        "half_angle = nan",
        "half_angle",
        "must be a finite number",
    );
    reject_shape(
        CONE,
        "axis = [0, 2]",
        "axis = [0.0, -0.0]",
        "axis",
        "the axis must be a nonzero vector",
    );
    reject_shape(
        CONE,
        "axis = [0, 2]",
        "axis = [0, 2, 0]",
        "axis",
        "has 3 components but apex has 2",
    );
    reject_shape(
        CONE,
        "apex = [0, 0.99]",
        "apex = [0, 0.99]\nradius = 1",
        "radius",
        "unknown key in [contact.obstacle]; allowed keys: type, apex, axis, half_angle",
    );
}

#[test]
fn reject_bad_pyramid_and_punch_obstacles() {
    reject_shape(PYRAMID, "faces = 4\n", "", "faces", "missing required key");
    reject_shape(
        PYRAMID,
        "faces = 4",
        "faces = 2",
        "faces",
        "must be an integer from 3 to 64, got 2",
    );
    reject_shape(
        PYRAMID,
        "faces = 4",
        "faces = 65",
        "faces",
        "must be an integer from 3 to 64, got 65",
    );
    reject_shape(
        PYRAMID,
        "faces = 4",
        "faces = -4",
        "faces",
        "must be an integer from 3 to 64, got -4",
    );
    reject_shape(
        PYRAMID,
        "faces = 4",
        "faces = 4.0",
        "faces",
        "expected an integer, found",
    );
    reject_shape(
        PYRAMID,
        "faces = 4",
        "faces = \"4\"",
        "faces",
        "expected an integer, found",
    );
    reject_shape(
        PYRAMID,
        "half_angle = 68",
        "half_angle = 90",
        "half_angle",
        "must be in (0, 90) degrees, got 90",
    );
    reject_shape(
        PYRAMID,
        "azimuth = 45",
        "azimuth = \"north\"",
        "azimuth",
        "expected a number",
    );
    reject_shape(
        PYRAMID,
        "azimuth = 45",
        "azimuth = inf",
        "azimuth",
        "must be a finite number",
    );
    reject_shape(
        PYRAMID,
        "axis = [0, 0, 1]",
        "axis = [0, 0]",
        "axis",
        "has 2 components but apex has 3",
    );
    reject_shape(
        PYRAMID,
        "azimuth = 45",
        "azimuth = 45\nedge_radius = 0",
        "edge_radius",
        "allowed keys: type, apex, axis, half_angle, faces, azimuth",
    );
    reject_shape(
        PUNCH,
        "center = [0, 0, 0.49]\n",
        "",
        "center",
        "missing required key",
    );
    reject_shape(
        PUNCH,
        "radius = 0.3\n",
        "",
        "radius",
        "missing required key",
    );
    reject_shape(
        PUNCH,
        "radius = 0.3",
        "radius = -0.3",
        "radius",
        "must be > 0, got -0.3",
    );
    reject_shape(
        PUNCH,
        "edge_radius = 0.05",
        "edge_radius = 0.31",
        "edge_radius",
        "must lie in [0, radius] = [0, 0.3], got 0.31",
    );
    reject_shape(
        PUNCH,
        "edge_radius = 0.05",
        "edge_radius = -0.01",
        "edge_radius",
        "must lie in [0, radius] = [0, 0.3], got -0.01",
    );
    reject_shape(
        PUNCH,
        "edge_radius = 0.05",
        "edge_radius = true",
        "edge_radius",
        "expected a number",
    );
    reject_shape(
        PUNCH,
        "axis = [0, 0, 0.5]",
        "axis = [0, 0, 0]",
        "axis",
        "the axis must be a nonzero vector",
    );
    reject_shape(
        PUNCH,
        "axis = [0, 0, 0.5]",
        "axis = [0, 0.5]",
        "axis",
        "has 2 components but center has 3",
    );
    reject_shape(
        PUNCH,
        "edge_radius = 0.05",
        "edge_radius = 0.05\nfaces = 4",
        "faces",
        "unknown key in [contact.obstacle]; allowed keys: type, center, axis, radius, edge_radius",
    );
}

#[test]
fn indenter_obstacles_against_mesh_dimension() {
    let g = groups(&[("c", 1)]);
    // A 2D mesh: the cylinder and the pyramid exist in 3D only; the message names the 2D shape.
    for (shape, instead) in [
        (CYLINDER, "\"sphere\" (a circle)"),
        (PYRAMID, "\"cone\" (a wedge)"),
    ] {
        let text = obstacle_case(MINIMAL, shape);
        let e = parse(&text).unwrap().check_against_mesh(2, &g).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("contact.obstacle.type"), "{e}");
        assert_eq!(e.line, Some(line(&text, "type = ")), "{e}");
        assert!(
            e.message
                .contains("is a 3D obstacle, but the mesh is 2D; in 2D use")
                && e.message.contains(instead),
            "{e}"
        );
    }
    // The cone (a wedge in 2D) and the punch (a strip in 2D) in both dimensions, with vectors
    // of the mesh's dimension.
    let two_d_punch = "type = \"punch\"\ncenter = [0, 1]\naxis = [0, 1]\nradius = 0.3\n";
    let three_d_cone = "type = \"cone\"\napex = [0, 0, 1]\naxis = [0, 0, 1]\nhalf_angle = 60\n";
    for shape in [CONE, two_d_punch] {
        let c = parse(&obstacle_case(MINIMAL, shape)).unwrap();
        c.check_against_mesh(2, &g).unwrap();
    }
    let g3 = groups(&[("c", 2)]);
    for shape in [CYLINDER, three_d_cone, PYRAMID, PUNCH] {
        let c = parse(&obstacle_case(&minimal_3d(), shape)).unwrap();
        c.check_against_mesh(3, &g3).unwrap();
    }
    for (base, dim, shape, key, needle) in [
        (MINIMAL.to_string(), 2, PUNCH, "center", "center"),
        (MINIMAL.to_string(), 2, three_d_cone, "apex", "apex"),
        (minimal_3d(), 3, CONE, "apex", "apex"),
        (minimal_3d(), 3, two_d_punch, "center", "center"),
    ] {
        let text = obstacle_case(&base, shape);
        let gg = if dim == 2 { &g } else { &g3 };
        let e = parse(&text)
            .unwrap()
            .check_against_mesh(dim, gg)
            .unwrap_err();
        assert_eq!(
            e.key.as_deref(),
            Some(format!("contact.obstacle.{key}").as_str()),
            "{e}"
        );
        assert_eq!(e.line, Some(line(&text, needle)), "{e}");
        assert!(
            e.message
                .contains(&format!("but the mesh is {dim}D and needs {dim}")),
            "{e}"
        );
    }
}

#[test]
fn obstacle_specs_become_obstacles() {
    use crate::contact::obstacle::{Cone, Punch, Pyramid};
    use crate::contact::{Obstacle, ObstacleError, Plane, Sphere};
    // Plane and sphere: exactly what their constructors give.
    let p = ObstacleSpec::Plane {
        point: vec![0.0, -1.0],
        normal: vec![0.6, 0.8],
    };
    assert_eq!(
        p.to_obstacle(2),
        Ok(Obstacle::Plane(
            Plane::new([0.0, -1.0, 0.0], [0.6, 0.8, 0.0], 2).unwrap()
        ))
    );
    let s = ObstacleSpec::Sphere {
        center: vec![0.0, 0.0, 1.0],
        radius: 0.5,
    };
    assert_eq!(
        s.to_obstacle(3),
        Ok(Obstacle::Sphere(
            Sphere::new([0.0, 0.0, 1.0], 0.5, 3).unwrap()
        ))
    );
    // The indenters carry their data over (angles in degrees).
    let o = spec(CONE).to_obstacle(2).unwrap();
    assert_eq!(
        o,
        Obstacle::Cone(Cone::new([0.0, 0.99, 0.0], [0.0, 1.0, 0.0], 70.0, 2).unwrap())
    );
    assert_eq!(o.dim(), 2);
    let o = spec(PYRAMID).to_obstacle(3).unwrap();
    assert_eq!(
        o,
        Obstacle::Pyramid(
            Pyramid::new([0.0, 0.0, 0.49], [0.0, 0.0, 1.0], 68.0, 4, 45.0, 3).unwrap()
        )
    );
    // Vickers at azimuth 45°: face 0 faces (1, 1, 0)/√2 horizontally.
    let Obstacle::Pyramid(py) = o else {
        unreachable!()
    };
    let m = py.face_normal(0);
    assert!(
        (m[0] - m[1]).abs() < 1e-15 && m[0] > 0.0 && m[2] < 0.0,
        "{m:?}"
    );
    let o = spec(PUNCH).to_obstacle(3).unwrap();
    assert_eq!(
        o,
        Obstacle::Punch(Punch::new([0.0, 0.0, 0.49], [0.0, 0.0, 1.0], 0.3, 0.05, 3).unwrap())
    );
    // The flat face lies at z = 0.49: a point at z = 0.5 under it penetrates by 0.01.
    let q = o.project([0.1, 0.0, 0.5]).unwrap();
    assert!((q.gap + 0.01).abs() < 1e-15 && q.normal == [0.0, 0.0, -1.0]);
    let o = spec(CYLINDER).to_obstacle(3).unwrap();
    assert!(matches!(o, Obstacle::Cylinder(_)) && o.dim() == 3);
    assert_eq!(
        spec(CYLINDER).to_obstacle(2),
        Err(ObstacleError::Only3D("cylinder"))
    );
    assert_eq!(spec(CONE).type_name(), "cone");
}

#[test]
fn mesh_project_takes_every_shape() {
    let text = replace(
        MINIMAL,
        "file = \"meshes/plate.msh\"\n",
        "file = \"meshes/plate.msh\"\nrefine = 1\n\n[[mesh.project]]\ngroup = \"hole\"\n\
         shape = { type = \"cylinder\", point = [0, 0, 0], axis = [0, 0, 1], radius = 1 }\n",
    );
    let c = parse(&text).unwrap();
    assert!(matches!(
        c.mesh.project[0].shape,
        ObstacleSpec::Cylinder { radius, .. } if radius == 1.0
    ));
    c.check_projections(3, &groups(&[("hole", 2)])).unwrap();
    let e = c.check_projections(2, &groups(&[("hole", 1)])).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("mesh.project[0].shape.type"), "{e}");
    assert_eq!(e.line, Some(line(&text, "shape = ")), "{e}");
    assert!(e.message.contains("in 2D use \"sphere\""), "{e}");
    expect_err(
        &replace(&text, "radius = 1", "radius = 1, half_angle = 3"),
        "mesh.project[0].shape.half_angle",
        "shape = ",
    );
}

#[test]
fn contact_motion_vector_or_table() {
    let c = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n";
    let motion = |m: &str| {
        parse(&with(&format!("{c}motion = {m}\n")))
            .expect("valid")
            .contacts
            .swap_remove(0)
            .motion
            .expect("motion")
    };
    let m = motion("[0.5, -2]");
    assert_eq!(
        (m.value.clone(), m.ramp, m.key.as_str()),
        (vec![0.5, -2.0], true, "contact.motion")
    );
    // t·m while it ramps, m when held
    assert_eq!(m.at(0.25), [0.125, -0.5, 0.0]);
    let held = motion("{ value = [0, 0, -0.1], ramp = false }");
    assert_eq!(
        (held.value.clone(), held.ramp),
        (vec![0.0, 0.0, -0.1], false)
    );
    assert_eq!(held.key, "contact.motion.value");
    assert_eq!(held.at(0.25), [0.0, 0.0, -0.1]);
    assert!(motion("{ value = [1, 2] }").ramp);
    // no motion: the obstacle stays
    let none = parse(&with(c))
        .unwrap()
        .contacts
        .into_iter()
        .next()
        .unwrap()
        .motion;
    assert_eq!(none, None);
}

#[test]
fn reject_bad_motion() {
    let c = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n";
    for (m, key) in [
        ("\"up\"", "contact.motion"),
        ("[0, nan]", "contact.motion[1]"),
        ("[0, inf]", "contact.motion[1]"),
        ("[1]", "contact.motion"),
        ("[1, 2, 3, 4]", "contact.motion"),
        ("[0, \"a\"]", "contact.motion[1]"),
        ("{ ramp = false }", "contact.motion.value"),
        ("{ value = [0, 1], ramp = \"no\" }", "contact.motion.ramp"),
        ("{ value = [0, 1], speed = 2 }", "contact.motion.speed"),
    ] {
        expect_err(&with(&format!("{c}motion = {m}\n")), key, "motion");
    }
    // the length is checked against the mesh: 3 components on a 2D mesh, 2 on a 3D one
    let text = with(&format!("{c}motion = [0, 0, 1]\n"));
    let e = parse(&text)
        .unwrap()
        .check_against_mesh(2, &groups(&[("c", 1)]))
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.motion"), "{e}");
    assert_eq!(e.line, Some(line(&text, "motion")), "{e}");
    assert!(e.message.contains("3 components"), "{e}");
    let text = with(&format!("{c}motion = {{ value = [0, 1], ramp = false }}\n"));
    let e = parse(&text)
        .unwrap()
        .check_against_mesh(2, &groups(&[("c", 1)]));
    assert!(e.is_ok(), "{e:?}");
    let e = replace(&text, "model = \"plane_strain\"\n", "");
    let e = replace(
        &e,
        "point = [0, 0], normal = [0, 1]",
        "point = [0, 0, 0], normal = [0, 0, 1]",
    );
    let e = parse(&e)
        .unwrap()
        .check_against_mesh(3, &groups(&[("c", 2)]))
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.motion.value"), "{e}");
}

/// `motion = { table = [[t, x, y], ...] }`: piecewise linear in the load factor, per component.
#[test]
fn contact_motion_table() {
    let c = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n";
    let text = with(&format!(
        "{c}motion = {{ table = [[0.0, 0.0, 0.0], [0.5, 0.0, -0.01], [1.0, 0.005, -0.01]] }}\n"
    ));
    let case = parse(&text).expect("valid");
    let m = case.contacts[0].motion.clone().expect("motion");
    assert_eq!(m.key, "contact.motion.table");
    assert_eq!(m.table.len(), 3);
    assert_eq!(m.last_factor(), Some(1.0));
    assert_eq!(m.at(0.0), [0.0, 0.0, 0.0]);
    assert_eq!(m.at(0.25), [0.0, -0.005, 0.0]);
    assert_eq!(m.at(0.5), [0.0, -0.01, 0.0]);
    assert_eq!(m.at(0.75), [0.0025, -0.01, 0.0]);
    assert_eq!(m.at(1.0), [0.005, -0.01, 0.0]);
    case.check_against_mesh(2, &groups(&[("c", 1)])).unwrap();
    // 3D rows on a 2D mesh: the row is named
    let e = parse(&replace(
        &text,
        "[[0.0, 0.0, 0.0], [0.5, 0.0, -0.01], [1.0, 0.005, -0.01]]",
        "[[0, 0, 0, 0], [1, 0, 0, -0.01]]",
    ))
    .unwrap()
    .check_against_mesh(2, &groups(&[("c", 1)]))
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact.motion.table[0]"), "{e}");
    assert!(e.message.contains("1 + 2 numbers"), "{e}");
    // a force table too; under [load] it covers every factor, a force never zero at one
    let f = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n\
             force = { table = [[0, 0, -1], [1, 0.3, -1]] }\n";
    let case = parse(&with(f)).expect("valid");
    assert_eq!(
        case.contacts[0].force.as_ref().unwrap().at(0.5),
        [0.15, -1.0, 0.0]
    );
}

#[test]
fn reject_bad_motion_table() {
    let c = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n";
    for (m, key, why) in [
        (
            "{ table = [[0, 0, 0]] }",
            "contact.motion.table",
            "at least two rows",
        ),
        (
            "{ table = [] }",
            "contact.motion.table",
            "at least two rows",
        ),
        ("{ table = [0, 1] }", "contact.motion.table[0]", "row"),
        (
            "{ table = [[0, 0], [1, 0]] }",
            "contact.motion.table[0]",
            "got 2",
        ),
        (
            "{ table = [[0, 0, 0], [1, 0, 0, 0]] }",
            "contact.motion.table[1]",
            "like the first row",
        ),
        (
            "{ table = [[0.1, 0, 0], [1, 0, 0]] }",
            "contact.motion.table[0][0]",
            "must be 0",
        ),
        (
            "{ table = [[0, 0, 0], [0.5, 0, 0], [0.5, 0, 1]] }",
            "contact.motion.table[2][0]",
            "must increase",
        ),
        (
            "{ table = [[0, 0, 0], [1, 0, 0], [0.5, 0, 1]] }",
            "contact.motion.table[2][0]",
            "must increase",
        ),
        (
            "{ table = [[0, 0, 0], [1, 0, nan]] }",
            "contact.motion.table[1][2]",
            "",
        ),
        (
            "{ table = [[0, 0, 0], [1, 0, \"a\"]] }",
            "contact.motion.table[1][2]",
            "",
        ),
        (
            "{ table = [[0, 0, 0], [1, 0, 1]], ramp = false }",
            "contact.motion.ramp",
            "no 'contact.motion.ramp'",
        ),
        (
            "{ table = [[0, 0, 0], [1, 0, 1]], value = [0, 1] }",
            "contact.motion.value",
            "whole history",
        ),
        // without [load] the run solves at factor 1: the table must reach it
        (
            "{ table = [[0, 0, 0], [0.5, 0, 1]] }",
            "contact.motion.table",
            "not extrapolated",
        ),
    ] {
        let e = expect_err(&with(&format!("{c}motion = {m}\n")), key, "motion");
        assert!(e.message.contains(why), "{m}: {e}");
    }
    // under [load], the largest factor counts
    let text = with(&format!(
        "{c}motion = {{ table = [[0, 0, 0], [1, 0, 1]] }}\n[load]\nfactors = [0.5, 1.2, 0.4]\n"
    ));
    let e = expect_err(&text, "contact.motion.table", "motion");
    assert!(e.message.contains("load.factors reaches 1.2"), "{e}");
    parse(&replace(&text, "[1, 0, 1]", "[1.2, 0, 1]")).expect("covers 1.2");
    // a force table that is zero at a planned factor
    let text = with(&format!(
        "{c}force = {{ table = [[0, 0, 0], [1, 0, -1]] }}\n[load]\nfactors = [0.0, 0.5, 1.0]\n"
    ));
    let e = expect_err(&text, "contact.force.table", "force");
    assert!(e.message.contains("zero force at the load factor 0"), "{e}");
    parse(&replace(&text, "[0.0, 0.5, 1.0]", "[0.5, 1.0]")).expect("not solved at 0");
}

/// Two `[[contact]]` tables: each pair keeps its keys under `contact[i]`.
#[test]
fn several_contact_pairs() {
    let two = "[[contact]]\ngroup = \"a\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n\
               [[contact]]\ngroup = \"b\"\nobstacle = { type = \"plane\", point = [0, 1], normal = [0, -1] }\n\
               motion = [0, -0.1]\nfriction = { law = \"tresca\", threshold = 0.2 }\n";
    let c = parse(&with(two)).expect("valid");
    assert_eq!(c.contacts.len(), 2);
    // Coulomb pairs with their own μ, next to a frictionless one
    let coulomb = |mu: f64| {
        format!(
            "[[contact]]\ngroup = \"g{mu}\"\nobstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1] }}\n\
             friction = {{ law = \"coulomb\", mu = {mu} }}\n"
        )
    };
    let mixed = format!(
        "{}{}[[contact]]\ngroup = \"free\"\nobstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1] }}\n",
        coulomb(0.2),
        coulomb(0.5)
    );
    let m = parse(&with(&mixed)).expect("valid");
    assert_eq!(m.contacts.len(), 3);
    assert!(matches!(m.contacts[1].friction, Friction::Coulomb { mu, .. } if mu == 0.5));
    assert_eq!(
        (c.contacts[0].key.as_str(), c.contacts[0].group.as_str()),
        ("contact[0]", "a")
    );
    assert_eq!(c.contacts[1].key, "contact[1]");
    assert_eq!(c.contacts[0].friction, Friction::None);
    assert_eq!(c.contacts[1].friction, Friction::Tresca { threshold: 0.2 });
    let m = c.contacts[1].motion.as_ref().expect("motion");
    assert_eq!(
        (m.value.clone(), m.key.as_str()),
        (vec![0.0, -0.1], "contact[1].motion")
    );
    // the single table stays valid, with its keys under `contact`
    let one = parse(&with(
        "[contact]\ngroup = \"a\"\nobstacle = { type = \"plane\", point = [0, 0], normal = [0, 1] }\n",
    ))
    .expect("valid");
    assert_eq!(one.contacts.len(), 1);
    assert_eq!(one.contacts[0].key, "contact");
    // every group is checked against the mesh, under its pair's key
    let e = c.check_against_mesh(2, &groups(&[("a", 1)])).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact[1].group"), "{e}");
    assert!(c
        .check_against_mesh(2, &groups(&[("a", 1), ("b", 1)]))
        .is_ok());
}

/// What several pairs must agree on, each refusal naming the key of the pair that breaks it.
#[test]
fn reject_bad_contact_pairs() {
    let pair = |group: &str, extra: &str| {
        format!(
            "[[contact]]\ngroup = \"{group}\"\nobstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1] }}\n{extra}"
        )
    };
    let coulomb = "friction = { law = \"coulomb\", mu = 0.3 }\n";
    for (text, key, needle, what) in [
        (
            format!("{}{}", pair("a", ""), pair("a", "")),
            "contact[1].group",
            "already the group of contact[0]",
            None,
        ),
        (
            format!(
                "{}{}",
                pair("a", "force = [0, -1]\n"),
                pair("b", "force = [0, 0]\n")
            ),
            "contact[1].force",
            "is zero",
            Some("force = [0, 0]"),
        ),
        (
            format!(
                "{}{}",
                pair("a", "force = [0, -1]\n"),
                pair("b", "force = [0, 2]\nmotion = [0, 1]\n")
            ),
            "contact[1].force",
            "instead of the motion",
            None,
        ),
        (
            format!(
                "{}{}",
                pair("a", coulomb),
                pair("b", "friction = { law = \"tresca\", threshold = 1 }\n")
            ),
            "contact[1].friction",
            "do not mix",
            Some("threshold = 1"),
        ),
        (
            format!(
                "{}{}",
                pair("a", coulomb),
                pair(
                    "b",
                    "friction = { law = \"coulomb\", mu = 0.4, algorithm = \"fixed-point\" }\n"
                )
            ),
            "contact[1].friction",
            "same algorithm",
            Some("mu = 0.4"),
        ),
        (
            format!("{}{}", pair("a", ""), pair("b", "rigid_modes = \"none\"\n")),
            "contact[1].rigid_modes",
            "handled one way",
            Some("rigid_modes"),
        ),
        (
            format!("{}{}", pair("a", ""), pair("b", "moton = [0, 1]\n")),
            "contact[1].moton",
            "",
            Some("moton"),
        ),
    ] {
        let text = with(&text);
        let e = parse(&text).expect_err(key);
        assert_eq!(e.key.as_deref(), Some(key), "{e}");
        assert!(e.message.contains(needle), "{e}");
        // the line of the offending key; a key that is missing: its pair's table
        match what {
            Some(needle) => assert_eq!(e.line, Some(line(&text, needle)), "{e}"),
            None => assert!(e.line.is_some(), "{e}"),
        }
    }
    let e = parse(&format!("contact = []\n{MINIMAL}")).expect_err("empty");
    assert_eq!(e.key.as_deref(), Some("contact"), "{e}");
    assert!(e.message.contains("at least one"), "{e}");
}

/// Force control on several pairs: each pair with `force` keeps its own force (and ramp), the
/// others their motion.
#[test]
fn force_control_on_several_pairs() {
    let pair = |group: &str, extra: &str| {
        format!(
            "[[contact]]\ngroup = \"{group}\"\nobstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1] }}\n{extra}"
        )
    };
    let text = with(&format!(
        "{}{}{}",
        pair("a", "force = [0, -1]\n"),
        pair("b", "force = { value = [0.5, 2], ramp = false }\n"),
        pair("c", "motion = [0, 0.25]\n")
    ));
    let c = parse(&text).unwrap();
    let forces: Vec<_> = c
        .contacts
        .iter()
        .map(|p| {
            p.force
                .as_ref()
                .map(|m| (m.value.clone(), m.ramp, m.key.clone()))
        })
        .collect();
    assert_eq!(
        forces,
        vec![
            Some((vec![0.0, -1.0], true, "contact[0].force".to_string())),
            Some((vec![0.5, 2.0], false, "contact[1].force.value".to_string())),
            None
        ]
    );
    assert!(c.contacts[2].motion.is_some());
    assert!(c.contacts[..2].iter().all(|p| p.motion.is_none()));
    assert!(c
        .check_against_mesh(2, &groups(&[("a", 1), ("b", 1), ("c", 1)]))
        .is_ok());
}

/// Force control with Coulomb friction: the fixed point (Tresca solves under force control)
/// and the generalised Newton (the default algorithm) are both accepted, on one pair and next
/// to other force-controlled pairs; pairs that mix the two algorithms are still refused.
#[test]
fn force_control_with_coulomb_takes_either_algorithm() {
    let fixed = "friction = { law = \"coulomb\", mu = 0.3, algorithm = \"fixed-point\" }\n";
    let one = with(&format!(
        "[contact]\ngroup = \"a\"\nobstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1] }}\nforce = [0, -1]\n{fixed}"
    ));
    let c = parse(&one).unwrap();
    assert!(matches!(
        c.contacts[0].friction,
        Friction::Coulomb {
            algorithm: CoulombAlgorithm::FixedPoint,
            ..
        }
    ));
    let c = parse(&one.replace(", algorithm = \"fixed-point\"", "")).unwrap();
    assert!(matches!(
        c.contacts[0].friction,
        Friction::Coulomb {
            algorithm: CoulombAlgorithm::Newton,
            ..
        }
    ));
    let pair = |group: &str, extra: &str| {
        format!(
            "[[contact]]\ngroup = \"{group}\"\nobstacle = {{ type = \"plane\", point = [0, 0], normal = [0, 1] }}\n{extra}"
        )
    };
    let two = with(&format!(
        "{}{}",
        pair("a", &format!("force = [0, -1]\n{fixed}")),
        pair("b", &format!("force = [0, 2]\n{fixed}"))
    ));
    assert_eq!(parse(&two).unwrap().contacts.len(), 2);
    let newton = "friction = { law = \"coulomb\", mu = 0.3 }\n";
    let text = with(&format!(
        "{}{}",
        pair("a", &format!("motion = [0, 1]\n{newton}")),
        pair("b", &format!("force = [0, 2]\n{newton}"))
    ));
    assert_eq!(parse(&text).unwrap().contacts.len(), 2);
    // a Coulomb pair (the generalised Newton) next to frictionless force-controlled pairs
    let text = with(&format!(
        "{}{}{}",
        pair("a", "force = [0, -1]\n"),
        pair("b", "force = [0, 2]\n"),
        pair("c", newton)
    ));
    assert_eq!(parse(&text).unwrap().contacts.len(), 3);
    let mixed = with(&format!(
        "{}{}",
        pair("a", &format!("force = [0, -1]\n{fixed}")),
        pair("b", &format!("force = [0, 2]\n{newton}"))
    ));
    let e = parse(&mixed).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contact[1].friction"), "{e}");
    assert!(e.message.contains("same algorithm"), "{e}");
}

#[test]
fn body_force_expressions() {
    let c = parse(&with(
        "[body_force]\nexpr = [\"-x*y\", \"2*sin(pi*x) + y^2\"]\n",
    ))
    .unwrap();
    let Some(BodyForceSpec::Expr(es)) = &c.body_force else {
        panic!("{:?}", c.body_force)
    };
    assert_eq!(es.len(), 2);
    assert_eq!(es[0].eval([2.0, 3.0, 0.0]), -6.0);
    assert!((es[1].eval([0.5, 3.0, 0.0]) - 11.0).abs() < 1e-15);
    assert!(c.check_against_mesh(2, &[]).is_ok());
    assert_eq!(c.body_force.as_ref().unwrap().key(), "body_force.expr");
    // A 3D expression may read z.
    let text = replace(MINIMAL, "model = \"plane_strain\"\n", "")
        + "[body_force]\nexpr = [\"0\", \"0\", \"-z\"]\n";
    assert!(parse(&text).unwrap().check_against_mesh(3, &[]).is_ok());
    // --set reaches the expressions.
    let c = parse_set(MINIMAL, &["body_force.expr=[\"1\", \"y\"]"]).unwrap();
    assert!(matches!(&c.body_force, Some(BodyForceSpec::Expr(e)) if e[1].text() == "y"));
}

#[test]
fn reject_bad_body_force_expressions() {
    let e = expect_err(
        &with("[body_force]\nexpr = [\"x\", \"sin(x\"]\n"),
        "body_force.expr[1]",
        "expr = ",
    );
    assert!(e.message.contains("cannot parse"), "{e}");
    let e = expect_err(
        &with("[body_force]\nexpr = [\"t*x\", \"0\"]\n"),
        "body_force.expr[0]",
        "expr = ",
    );
    assert!(e.message.contains("unknown variable 't'"), "{e}");
    let e = expect_err(
        &with("[body_force]\nexpr = [\"foo(x)\", \"0\"]\n"),
        "body_force.expr[0]",
        "expr = ",
    );
    assert!(e.message.contains("unknown function 'foo'"), "{e}");
    let e = expect_err(
        &with("[body_force]\nexpr = [\"0\"]\n"),
        "body_force.expr",
        "expr = ",
    );
    assert!(e.message.contains("2 or 3"), "{e}");
    expect_err(
        &with("[body_force]\nexpr = [\"0\", 1]\n"),
        "body_force.expr[1]",
        "expr = ",
    );
    expect_err(
        &with("[body_force]\nexpr = \"x\"\n"),
        "body_force.expr",
        "expr = ",
    );
    let e = expect_err(
        &with("[body_force]\nvalue = [0, 0]\nexpr = [\"0\", \"0\"]\n"),
        "body_force.expr",
        "expr = ",
    );
    assert!(e.message.contains("not both"), "{e}");
    let e = expect_err(&with("[body_force]\n"), "body_force", "[body_force]");
    assert!(
        e.message.contains("value") && e.message.contains("expr"),
        "{e}"
    );
    // Against the mesh: the number of components, z in 2D.
    let text = with("[body_force]\nexpr = [\"0\", \"0\", \"1\"]\n");
    let e = parse(&text)
        .unwrap()
        .check_against_mesh(2, &[])
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("body_force.expr"), "{e}");
    assert_eq!(e.line, Some(line(&text, "expr = ")));
    let text = with("[body_force]\nexpr = [\"0\", \"z\"]\n");
    let e = parse(&text)
        .unwrap()
        .check_against_mesh(2, &[])
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("body_force.expr[1]"), "{e}");
    assert!(e.message.contains("'z'") && e.message.contains("2D"), "{e}");
}

const TWO_MATERIALS: &str = r#"[mesh]
file = "meshes/bar.msh"

[[material]]
group = "soft"
young = 1.0
poisson = 0.25
model = "plane_strain"

[[material]]
group = "hard"
young = 3.0
poisson = 0.3
model = "plane_strain"
"#;

#[test]
fn materials_read_in_file_order_with_their_groups_and_keys() {
    let c = parse(TWO_MATERIALS).unwrap();
    let got: Vec<(&str, Option<&str>, f64)> = c
        .materials
        .iter()
        .map(|m| (m.key.as_str(), m.group.as_deref(), m.young))
        .collect();
    assert_eq!(
        got,
        [
            ("material[0]", Some("soft"), 1.0),
            ("material[1]", Some("hard"), 3.0)
        ]
    );
    assert_eq!(c.model(2).unwrap(), MaterialModel::PlaneStrain);
    let single = parse(MINIMAL).unwrap();
    assert_eq!(single.materials.len(), 1);
    assert_eq!(single.materials[0].key, "material");
    assert_eq!(single.materials[0].group, None);
}

#[test]
fn materials_reject_a_missing_group_two_models_and_a_group_named_twice() {
    let no_group = replace(TWO_MATERIALS, "group = \"hard\"\n", "");
    let e = parse(&no_group).expect_err("no group");
    assert_eq!(e.key.as_deref(), Some("material[1].group"), "{e}");
    let models = replace(
        TWO_MATERIALS,
        "poisson = 0.3\nmodel = \"plane_strain\"",
        "poisson = 0.3\nmodel = \"plane_stress\"",
    );
    let e = expect_err(&models, "material[1].model", "model = \"plane_stress\"");
    assert!(e.to_string().contains("material[0].model"), "{e}");
    let twice = replace(TWO_MATERIALS, "group = \"hard\"", "group = \"soft\"");
    let e = parse(&twice).expect_err("a group named twice");
    assert_eq!(e.key.as_deref(), Some("material[1].group"), "{e}");
    assert_eq!(e.line, Some(11), "{e}");
    // [material] has no group key; [material] and [[material]] together are a TOML error
    let e = parse(&replace(
        MINIMAL,
        "young = 2.0",
        "group = \"a\"\nyoung = 2.0",
    ))
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material.group"), "{e}");
    assert!(parse(&format!(
        "{TWO_MATERIALS}\n[material]\nyoung = 1.0\npoisson = 0.2\n"
    ))
    .is_err());
    // the model is required of every material of a 2D mesh, named by its key
    let no_model = replace(
        TWO_MATERIALS,
        "poisson = 0.3\nmodel = \"plane_strain\"",
        "poisson = 0.3",
    );
    let c = parse(&no_model).unwrap();
    let e = c.model(2).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material[1]"), "{e}");
    assert!(
        e.to_string().contains("material[1].model is required"),
        "{e}"
    );
}

#[test]
fn material_groups_must_be_volume_groups_of_the_mesh() {
    let c = parse(TWO_MATERIALS).unwrap();
    let g = |names: &[(&str, usize)]| -> Vec<(String, usize)> {
        names.iter().map(|(n, d)| (n.to_string(), *d)).collect()
    };
    c.check_against_mesh(2, &g(&[("soft", 2), ("hard", 2)]))
        .unwrap();
    let e = c
        .check_against_mesh(2, &g(&[("soft", 2), ("hard", 1)]))
        .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material[1].group"), "{e}");
    assert!(e.to_string().contains("volume group"), "{e}");
    let e = c.check_against_mesh(2, &g(&[("soft", 2)])).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("material[1].group"), "{e}");
}

#[test]
fn solver_path_values_and_what_reuse_implies_without_it() {
    let solver = |text: &str| parse(&with(text)).unwrap().solver;
    let s = solver("");
    assert_eq!((s.path, s.reuse), (SolverPath::Auto, Reuse::Auto));
    for (name, want) in [
        ("auto", SolverPath::Auto),
        ("schur", SolverPath::Schur),
        ("plain", SolverPath::Plain),
    ] {
        let s = solver(&format!("[solver]\npath = \"{name}\"\n"));
        assert_eq!((s.path, s.reuse), (want, Reuse::Auto));
        assert_eq!(want.name(), name);
    }
    // without `path`: "never" and "always" are the plain path's, "condensed" (the former
    // name of the default) the default
    for (reuse, path, want) in [
        ("auto", SolverPath::Auto, Reuse::Auto),
        ("never", SolverPath::Plain, Reuse::Never),
        ("always", SolverPath::Plain, Reuse::Always),
        ("condensed", SolverPath::Auto, Reuse::Auto),
    ] {
        let s = solver(&format!("[solver]\nreuse = \"{reuse}\"\n"));
        assert_eq!((s.path, s.reuse), (path, want), "reuse = {reuse}");
    }
    // with it, reuse says only how the plain path carries a factorisation
    let s = solver("[solver]\npath = \"auto\"\nreuse = \"never\"\n");
    assert_eq!((s.path, s.reuse), (SolverPath::Auto, Reuse::Never));
    let s = solver("[solver]\npath = \"plain\"\nreuse = \"always\"\n");
    assert_eq!((s.path, s.reuse), (SolverPath::Plain, Reuse::Always));
    let s = solver("[solver]\npath = \"schur\"\nreuse = \"condensed\"\n");
    assert_eq!((s.path, s.reuse), (SolverPath::Schur, Reuse::Auto));
    let c = parse_set(MINIMAL, &["solver.path=\"plain\""]).unwrap();
    assert_eq!(c.solver.path, SolverPath::Plain);
    expect_err(&with("[solver]\npath = \"dense\"\n"), "solver.path", "path");
    expect_err(&with("[solver]\npath = 1\n"), "solver.path", "path");
}

#[test]
fn reject_schur_path_with_a_plain_reuse_or_another_path() {
    for reuse in ["never", "always"] {
        let text = with(&format!(
            "[solver]\npath = \"schur\"\nreuse = \"{reuse}\"\n"
        ));
        let e = expect_err(&text, "solver.reuse", "reuse");
        assert!(e.message.contains("whole solve"), "{e}");
    }
    for path in ["auto", "plain"] {
        let text = with(&format!(
            "[solver]\npath = \"{path}\"\nreuse = \"condensed\"\n"
        ));
        let e = expect_err(&text, "solver.reuse", "reuse");
        assert!(e.message.contains("Schur path"), "{e}");
    }
}

#[test]
fn reject_schur_path_where_it_cannot_run() {
    let contact = "[contact]\ngroup = \"c\"\nobstacle = { type = \"plane\", point = [0, 0], \
                   normal = [0, -1] }\n";
    let ok = with(&format!(
        "{contact}[solver]\npath = \"schur\"\npreset = \"direct\"\n"
    ));
    assert_eq!(parse(&ok).unwrap().solver.path, SolverPath::Schur);
    let coulomb = |alg: &str| {
        format!("friction = {{ law = \"coulomb\", mu = 0.3, algorithm = \"{alg}\" }}\n")
    };
    let cases = [
        ("preset = \"iterative\"\n", String::new(), "iterative"),
        ("method = \"snesvi\"\n", String::new(), "snesvi"),
        (
            "",
            "friction = { law = \"tresca\", threshold = 0.01 }\n[newton]\ninit = \"all_inactive\"\n"
                .into(),
            "Tresca",
        ),
        ("", coulomb("fixed-point"), "fixed point"),
        (
            "",
            coulomb("newton") + "[newton]\ninit = \"gap\"\n",
            "newton.init",
        ),
    ];
    for (solver, extra, says) in cases {
        let key = "path = \"schur\"";
        let text = with(&format!("[solver]\n{key}\n{solver}{contact}{extra}"));
        let e = expect_err(&text, "solver.path", key);
        assert!(e.message.contains(says), "{e}");
    }
    let newton = with(&format!(
        "{contact}{}[solver]\npath = \"schur\"\n",
        coulomb("newton")
    ));
    assert_eq!(parse(&newton).unwrap().solver.path, SolverPath::Schur);
    // Tresca from newton.init = "auto" (the default): on the contact unknowns
    let tresca = with(&format!(
        "{contact}friction = {{ law = \"tresca\", threshold = 0.01 }}\n[solver]\npath = \"schur\"\n"
    ));
    assert_eq!(parse(&tresca).unwrap().solver.path, SolverPath::Schur);
}
