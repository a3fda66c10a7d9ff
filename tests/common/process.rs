//! Running processes: the binary and the examples (under mpirun, with a time limit),
//! meshes with the gmsh CLI, case files, and Debian's Python (meshio, h5py, numpy).

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Debian's Python (meshio, h5py and numpy installed); the pyenv `python3` on PATH has none.
pub const PYTHON: &str = "/usr/bin/python3";

/// The signorini-mpi binary built for this test run.
pub fn binary() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_signorini-mpi"))
}

/// Absolute path of a file of the crate, e.g. `repo("cases/hertz/hertz.toml")`.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Directory of the committed test meshes.
pub fn mesh_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes")
}

/// Result of a finished process.
#[derive(Debug)]
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    /// The command, for failure messages.
    pub what: String,
}

impl Run {
    /// Command, exit code and both streams, for failure messages.
    pub fn output(&self) -> String {
        format!(
            "{}\nexit code {:?}\n--- stdout\n{}\n--- stderr\n{}",
            self.what, self.code, self.stdout, self.stderr
        )
    }

    /// The one `error` line on stderr of a refused run (exit code 2); panics with both streams
    /// unless the run exited with 2 and printed exactly one.
    pub fn the_error_line(&self, what: &str) -> &str {
        self.expect_code(2, what);
        let errors: Vec<&str> = (self.stderr.lines())
            .filter(|l| l.starts_with("error"))
            .collect();
        assert_eq!(
            errors.len(),
            1,
            "{what}: one error line:\n{}",
            self.output()
        );
        errors[0]
    }

    /// Panics with both streams if the exit code is not `code`.
    pub fn expect_code(&self, code: i32, what: &str) -> &Self {
        assert_eq!(
            self.code,
            Some(code),
            "{what}: exit code {:?}, expected {code}\n--- stdout\n{}\n--- stderr\n{}",
            self.code,
            self.stdout,
            self.stderr
        );
        self
    }
}

/// Runs `cmd` to completion; kills it and panics after `limit`. Output goes to temporary
/// files (not pipes), so a chatty child can never block on a full pipe.
pub fn run_with_timeout(mut cmd: Command, limit: Duration) -> Run {
    let dir = tempfile::tempdir().expect("tempdir");
    let out_path = dir.path().join("stdout");
    let err_path = dir.path().join("stderr");
    cmd.stdin(Stdio::null())
        .stdout(File::create(&out_path).expect("stdout file"))
        .stderr(File::create(&err_path).expect("stderr file"));
    let desc = format!("{cmd:?}");
    let mut child = cmd
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {desc}: {e}"));
    let start = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().expect("try_wait") {
            break st;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "{desc} did not finish within {limit:?} (hang?)\n--- stdout\n{}\n--- stderr\n{}",
                std::fs::read_to_string(&out_path).unwrap_or_default(),
                std::fs::read_to_string(&err_path).unwrap_or_default()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run {
        code: status.code(),
        stdout: std::fs::read_to_string(&out_path).unwrap_or_default(),
        stderr: std::fs::read_to_string(&err_path).unwrap_or_default(),
        what: desc,
    }
}

/// Environment every MPI process of the tests needs.
pub fn mpi_env(cmd: &mut Command) {
    cmd.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        // Yield instead of busy-polling when idle: the test machine is shared.
        .env("OMPI_MCA_mpi_yield_when_idle", "1")
        .env("OPENBLAS_NUM_THREADS", "1")
        .env("OMP_NUM_THREADS", "1")
        // Every mpirun its own session directory: with one shared /tmp/ompi.<host>.<uid>, an
        // mpirun that cleans up while another starts can remove the parent of the other's
        // new session directory ("orte_session_dir failed"; seen once in a full run).
        .env("OMPI_MCA_orte_tmpdir_base", session_dir());
}

/// A new, empty directory for one mpirun's session files.
fn session_dir() -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "signorini-tests-ompi/{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&d).expect("creating an Open MPI session directory");
    d
}

/// `mpirun -n np --oversubscribe program args...` with the MPI environment set.
pub fn mpirun(np: usize, program: &Path, args: &[String]) -> Command {
    mpirun_with(np, &[], program, args)
}

/// [`mpirun`] with options of mpirun's own before the program (e.g. `--bind-to none`).
pub fn mpirun_with(np: usize, options: &[&str], program: &Path, args: &[String]) -> Command {
    let mut cmd = Command::new("mpirun");
    cmd.args(["-n", &np.to_string(), "--oversubscribe"])
        .args(options)
        .arg(program)
        .args(args);
    mpi_env(&mut cmd);
    cmd
}

/// The signorini-mpi binary on `np` ranks (np = 0: started directly, MPI singleton).
pub fn solver(np: usize, args: &[String]) -> Command {
    if np == 0 {
        let mut cmd = Command::new(binary());
        cmd.args(args);
        mpi_env(&mut cmd);
        cmd
    } else {
        mpirun(np, &binary(), args)
    }
}

/// Path of an example binary of this crate, built once per test process with the same
/// profile as the running test (cargo test builds examples too; this makes sure).
pub fn example(name: &str) -> PathBuf {
    static BUILT: OnceLock<Mutex<Vec<String>>> = OnceLock::new();
    let exe = std::env::current_exe().expect("test executable path");
    // target/<profile>/deps/<test>-HASH → target/<profile>
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target dir")
        .to_path_buf();
    let bin = profile_dir.join("examples").join(name);
    let built = BUILT.get_or_init(|| Mutex::new(Vec::new()));
    let mut built = built.lock().unwrap_or_else(|e| e.into_inner());
    if !built.iter().any(|b| b == name) {
        let release = profile_dir.file_name().is_some_and(|n| n == "release");
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "--quiet", "--example", name])
            .current_dir(env!("CARGO_MANIFEST_DIR"));
        if release {
            cmd.arg("--release");
        }
        let st = cmd.status().expect("running cargo build --example");
        assert!(st.success(), "cargo build --example {name} failed");
        built.push(name.to_string());
    }
    assert!(bin.exists(), "{} missing", bin.display());
    bin
}

/// Generates a mesh with the gmsh CLI from a .geo of tests/meshes (`-setnumber h h`).
pub fn gmsh(geo: &str, dim: usize, h: f64, out: &Path) {
    gmsh_file(
        &mesh_dir().join(geo),
        dim,
        &["-setnumber", "h", &h.to_string()],
        out,
    );
}

/// Generates a `dim`-dimensional mesh (MSH 4.1) with the gmsh CLI from the .geo file `geo`,
/// with the extra arguments `extra` (e.g. `-setnumber h 0.06`).
pub fn gmsh_file(geo: &Path, dim: usize, extra: &[&str], out: &Path) {
    let mut cmd = Command::new("gmsh");
    cmd.arg(format!("-{dim}"))
        .arg(geo)
        .args(extra)
        .args(["-format", "msh41", "-o"])
        .arg(out);
    let r = run_with_timeout(cmd, Duration::from_secs(120));
    r.expect_code(0, &format!("gmsh {} {extra:?}", geo.display()));
    assert!(out.exists(), "gmsh wrote no {}", out.display());
}

/// Unit square (dim 2) or unit cube (dim 3) with mesh size h, written into `dir`.
pub fn unit_mesh(dir: &Path, dim: usize, h: f64) -> PathBuf {
    let (geo, stem) = if dim == 2 {
        ("square.geo", "square")
    } else {
        ("cube.geo", "cube")
    };
    let out = dir.join(format!("{stem}_h{h}.msh"));
    gmsh(geo, dim, h, &out);
    out
}

/// `signorini-mpi convert MSH H5` (one process); panics unless it exits with 0.
pub fn convert(msh: &Path, h5: &Path) {
    let args = [
        "convert".to_string(),
        msh.display().to_string(),
        h5.display().to_string(),
    ];
    run_with_timeout(solver(0, &args), Duration::from_secs(60)).expect_code(0, "convert");
}

/// The strip [0, 4] × [0, 0.02] as a structured gmsh mesh in `dir`: `top` nodes on its top, 4
/// layers, 8 (top − 1) triangles; the groups "bottom", "top" and "body".
pub fn strip_mesh(dir: &Path, top: usize) -> PathBuf {
    let geo = dir.join("strip.geo");
    std::fs::write(
        &geo,
        format!(
            "Point(1) = {{0, 0, 0}};\nPoint(2) = {{4, 0, 0}};\nPoint(3) = {{4, 0.02, 0}};\n\
             Point(4) = {{0, 0.02, 0}};\nLine(1) = {{1, 2}};\nLine(2) = {{2, 3}};\n\
             Line(3) = {{3, 4}};\nLine(4) = {{4, 1}};\nCurve Loop(1) = {{1, 2, 3, 4}};\n\
             Plane Surface(1) = {{1}};\nTransfinite Curve {{1, 3}} = {top};\n\
             Transfinite Curve {{2, 4}} = 5;\nTransfinite Surface {{1}};\n\
             Physical Curve(\"bottom\") = {{1}};\nPhysical Curve(\"top\") = {{3}};\n\
             Physical Surface(\"body\") = {{1}};\n"
        ),
    )
    .unwrap();
    let mesh = dir.join("strip.msh");
    gmsh_file(&geo, 2, &[], &mesh);
    mesh
}

/// Runs an inline Python script with /usr/bin/python3; panics with its output on failure.
pub fn python(script: &str, args: &[String]) -> String {
    let mut cmd = Command::new(PYTHON);
    cmd.arg("-c").arg(script).args(args);
    let r = run_with_timeout(cmd, Duration::from_secs(120));
    r.expect_code(0, "python check");
    r.stdout
}

/// Parses the last line of `text` that starts with `prefix` as JSON.
pub fn json_after(text: &str, prefix: &str) -> serde_json::Value {
    let line = text
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix(prefix))
        .unwrap_or_else(|| panic!("no line starting with {prefix:?} in:\n{text}"));
    serde_json::from_str(line.trim()).unwrap_or_else(|e| panic!("bad JSON {line:?}: {e}"))
}

/// All lines of `text` that start with `prefix`, parsed as JSON.
pub fn json_lines(text: &str, prefix: &str) -> Vec<serde_json::Value> {
    text.lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .map(|l| serde_json::from_str(l.trim()).unwrap_or_else(|e| panic!("bad JSON {l:?}: {e}")))
        .collect()
}

/// Writes a case file; `mesh` is written as an absolute path.
pub fn write_case(path: &Path, text: &str) -> PathBuf {
    std::fs::write(path, text).expect("write case");
    path.to_path_buf()
}

/// TOML string literal of a path.
pub fn toml_path(p: &Path) -> String {
    format!("{:?}", p.display().to_string())
}

/// Runs an inline Python script with /usr/bin/python3 and parses the last stdout line that
/// starts with "RESULT " as JSON; panics with its output on failure.
pub fn python_json(script: &str, args: &[&Path]) -> serde_json::Value {
    let mut cmd = Command::new(PYTHON);
    cmd.arg("-c").arg(script).args(args);
    let r = run_with_timeout(cmd, Duration::from_secs(120));
    assert_eq!(r.code, Some(0), "python failed:\n{}", r.output());
    let line = r
        .stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("RESULT "))
        .unwrap_or_else(|| panic!("no RESULT line:\n{}", r.output()));
    serde_json::from_str(line).unwrap_or_else(|e| panic!("bad JSON {line:?}: {e}"))
}
