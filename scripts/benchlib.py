"""The harness the bench scripts share (scripts/bench-*): paths, the build, the MPI environment,
solver runs with their outputs (summary.json, CSV files), medians, meshes made with gmsh or
scripts/mesh, and markdown tables. Import it from a script in scripts/:

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import benchlib as bl
"""

import csv
import datetime
import json
import math
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# the case files of the benchmarks; a run gives its mesh and parameters with --set
CASES = ROOT / "cases" / "bench"
RESULTS = ROOT / "bench" / "results"
MESHES = ROOT / "bench" / "meshes"
HERTZ_MESHES = ROOT / "cases" / "hertz" / "meshes"
BIN = ROOT / "target" / "release" / "signorini-mpi"


def target_bin():
    """The release binary of the build's target directory (CARGO_TARGET_DIR, as cargo reads it)."""
    return Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release" / "signorini-mpi"


def case(name):
    """A case file of cases/bench by its name without .toml."""
    return CASES / f"{name}.toml"


def mesh_set(mesh):
    """The --set entry giving a case its mesh file."""
    return f"mesh.file={json.dumps(str(mesh))}"


def build(no_build=False):
    """cargo build --release (quiet), unless no_build."""
    if not no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)


def mpi_env(threads_from_env=False, **extra):
    """The environment of every MPI run (scripts/lib.sh's mpi_env: one BLAS thread per rank,
    mpirun allowed as root, oversubscription allowed), plus `extra`. threads_from_env: keep
    OPENBLAS_NUM_THREADS and OMP_NUM_THREADS where the caller's environment sets them."""
    e = dict(os.environ)
    e.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
             OMPI_MCA_rmaps_base_oversubscribe="1")
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
        if threads_from_env:
            e.setdefault(k, "1")
        else:
            e[k] = "1"
    e.update(extra)
    return e


def solver_cmd(ranks, case_file, sets=(), out=None, binary=BIN, petsc=(), prefix=(), mpirun=()):
    """[prefix...] mpirun -n RANKS [mpirun...] BINARY CASE [-o OUT] [--set S]... [-- PETSC...]"""
    cmd = [*prefix, "mpirun", "-n", str(ranks), *mpirun, str(binary), str(case_file)]
    if out is not None:
        cmd += ["-o", str(out)]
    for s in sets:
        cmd += ["--set", s]
    if petsc:
        cmd += ["--", *petsc]
    return cmd


def run(cmd, timeout=None, env=None, merge=False):
    """Runs a command with the MPI environment (or `env`), its output captured as text (stderr
    into stdout with `merge`)."""
    err = subprocess.STDOUT if merge else subprocess.PIPE
    return subprocess.run(cmd, env=mpi_env() if env is None else env, stdout=subprocess.PIPE,
                          stderr=err, text=True, timeout=timeout)


def error_line(r, limit=None):
    """The first line of a failed run's output that starts with "error", else "exit CODE"."""
    err = [ln for ln in ((r.stderr or "") + (r.stdout or "")).splitlines()
           if ln.startswith("error")]
    text = err[0] if err else f"exit {r.returncode}"
    return text if limit is None else text[:limit]


def summary(out):
    """summary.json of an output directory."""
    return json.loads((Path(out) / "summary.json").read_text())


def read_csv(path):
    """The rows of a CSV file as dicts."""
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def median_solve(fn, repeat):
    """Calls fn() (a summary, or {"failed": ...}) repeat times: the median of timings.solve and
    the last summary; (None, the summary) at the first failure."""
    secs, last = [], None
    for _ in range(repeat):
        last = fn()
        if "failed" in last:
            return None, last
        secs.append(last["timings"]["solve"])
    return statistics.median(secs), last


def gmsh(geo, out, dim, numbers=(), binary=True):
    """Meshes geo with gmsh into out (MSH 4.1) unless out exists; numbers: (name, value) pairs
    for -setnumber. Returns out."""
    out = Path(out)
    if not out.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
        cmd = ["gmsh", f"-{dim}", str(geo)]
        for name, value in numbers:
            cmd += ["-setnumber", name, str(value)]
        cmd += ["-format", "msh41"] + (["-bin"] if binary else []) + ["-o", str(out)]
        subprocess.run(cmd, check=True, capture_output=True)
    return out


def hertz_mesh(level, refined=True, quiet=False):
    """cases/hertz/meshes/hertz[_refined]_L{level}.msh, made by scripts/mesh if missing."""
    m = HERTZ_MESHES / (f"hertz_refined_L{level}.msh" if refined else f"hertz_L{level}.msh")
    if not m.exists():
        cmd = [str(ROOT / "scripts" / "mesh"), "hertz", str(level)] + (["--refined"] if refined else [])
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL if quiet else None)
    return m


def ball_mesh(h, zone=None):
    """The ball of cases/ball3d/ball3d.geo at pole mesh size h in bench/meshes; with `zone` (a
    cap height) cut along that cap (group "zone")."""
    name = f"ball3d_h{h}_zone{zone:.4f}.msh" if zone is not None else f"ball3d_h{h}.msh"
    numbers = [("h", h)] + ([("zone", f"{zone:.6f}")] if zone is not None else [])
    return gmsh(ROOT / "cases" / "ball3d" / "ball3d.geo", MESHES / name, 3, numbers)


def block_mesh(h, directory=MESHES):
    """The block of cases/blocks/block3d.geo at mesh size h, in `directory`."""
    return gmsh(ROOT / "cases" / "blocks" / "block3d.geo", Path(directory) / f"block3d_h{h}.msh",
                3, [("h", h)])


def md_table(head, rows=()):
    """A markdown table: the header cells, the separator, one line per row of cells."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return lines


def write_result(path, text):
    """Writes text to path (its directory made if missing)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def log(msg):
    """A progress line on stderr."""
    print(msg, file=sys.stderr, flush=True)


def stamped_log(name):
    """A progress logger on stderr: "[NAME HH:MM:SS] message"."""
    def log_line(msg):
        print(f"[{name} {datetime.datetime.now():%H:%M:%S}] {msg}", file=sys.stderr, flush=True)
    return log_line


def uptime():
    """The output of uptime(1), or "?"."""
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "?"


def load1():
    """The 1-minute load average, or NaN."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def git_rev():
    """The short hash of the checkout's HEAD, or "?"."""
    r = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                       capture_output=True, text=True)
    return r.stdout.strip() or "?"


def parse_range(text):
    """'0-4' -> [0..4], '3' -> [3], '0,2,5' -> [0, 2, 5], '' / 'none' -> []."""
    if not text or text == "none":
        return []
    out = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            out += list(range(int(a), int(b) + 1))
        elif part:
            out.append(int(part))
    return out


def fmt(v, spec):
    """v formatted by spec; "–" for None, "" and NaN."""
    if v is None or v == "" or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return format(v, spec)
