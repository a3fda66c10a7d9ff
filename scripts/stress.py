"""The runner of scripts/stress: reads the runs from scripts/stress.toml (one row per run), runs
each under `timeout` through mpirun, judges it and prints the table. Run it through
scripts/stress (which sets up the environment); options and outcomes: see its header.

  --list   print the command of every run (after --quick / --only) instead of running them:
           family, case, variation, ranks, expected outcome and command, tab-separated; the
           newton.c of a "c" row (from the reference run) shown as FACTOR*E/h_c
"""
import json, math, os, shutil, subprocess, sys, tempfile, time, tomllib
from collections import OrderedDict
import h5py
import numpy as np

ROOT = os.environ["SIGNORINI_ROOT"]
BIN = os.environ["STRESS_BIN"]
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "stress.toml")

args = sys.argv[1:]
QUICK = False
LIST = False
MD = None
LIMIT = 60
ONLY = None
i = 0
while i < len(args):
    a = args[i]
    if a == "--quick":
        QUICK = True
    elif a == "--list":
        LIST = True
    elif a in ("--md", "--limit", "--only") and i + 1 < len(args):
        i += 1
        if a == "--md":
            MD = args[i]
        elif a == "--limit":
            LIMIT = int(args[i])
        else:
            ONLY = set(args[i].split(","))
    else:
        sys.exit(f"stress: unknown argument {a!r} (usage: scripts/stress [--quick] [--md FILE] "
                 "[--limit SECONDS] [--only FAMILY,...] [--list])")
    i += 1

KEEP = os.environ.get("STRESS_KEEP")
if LIST:
    WORK = None
elif KEEP:
    os.makedirs(KEEP, exist_ok=True)
    WORK = KEEP
else:
    WORK = tempfile.mkdtemp(prefix="stress-")


# ---------------------------------------------------------------------------------------
# Cases: file, base --set list, Young's modulus, Tresca threshold (None: no friction).
class Case:
    def __init__(self, name, file, sets=(), young=2.0, tresca=None):
        self.name, self.file, self.sets = name, os.path.join(ROOT, file), list(sets)
        self.young, self.tresca = young, tresca


def load_data(path):
    """The cases and the rows of the suite."""
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as e:
        print(f"stress: error: {path}: {e}", file=sys.stderr)
        sys.exit(2)
    def bad(msg):
        print(f"stress: error: {path}: {msg}", file=sys.stderr)
        sys.exit(2)

    cases = {}
    for name, c in data.get("cases", {}).items():
        if "file" not in c:
            bad(f"cases.{name} has no file")
        cases[name] = Case(name, c["file"], c.get("sets", ()), c.get("young", 2.0),
                           c.get("tresca"))
    rows = data.get("rows", [])
    for i, row in enumerate(rows):
        missing = [k for k in ("family", "case", "var", "ranks") if k not in row]
        if missing:
            bad(f"rows[{i}] has no {', '.join(missing)}")
        for c in [row["case"]] + [d["case"] for d in row.get("check", []) if "case" in d]:
            if c not in cases:
                bad(f"rows[{i}] names the case {c!r}, which [cases] does not define")
    return cases, rows


CASES, ROW_DATA = load_data(DATA)


def tval(v):
    """A value as TOML."""
    if isinstance(v, list):
        return "[" + ",".join(tval(x) for x in v) + "]"
    if isinstance(v, str):
        return v
    return repr(float(v))


# ---------------------------------------------------------------------------------------
# Running
class Result:
    pass


def shown(file, sets, np_):
    """The command of a run as the table's FAIL list shows it."""
    return " ".join(("'" + c + "'") if any(ch in c for ch in ' {}"[]') else c for c in
                    ["mpirun", "-n", str(np_), os.path.relpath(BIN, ROOT),
                     os.path.relpath(file, ROOT)] +
                    [x for s in sets for x in ("--set", s)] + ["-o", "OUT"])


CACHE = {}
COUNTER = [0]
TOTAL_RUN_SECONDS = [0.0]


def execute(case, sets=(), np_=1):
    """Runs the solver once (cached by case, sets and rank count)."""
    sets = tuple(case.sets) + tuple(sets)
    key = (case.name, sets, np_)
    if key in CACHE:
        return CACHE[key]
    COUNTER[0] += 1
    out = os.path.join(WORK, f"run{COUNTER[0]:04d}")
    shutil.rmtree(out, ignore_errors=True)
    cmd = ["timeout", "-k", "5", str(LIMIT), "mpirun", "-n", str(np_), "--oversubscribe",
           BIN, case.file]
    for s in sets:
        cmd += ["--set", s]
    cmd += ["-o", out]
    t0 = time.time()
    p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                       errors="replace")
    r = Result()
    r.secs = time.time() - t0
    TOTAL_RUN_SECONDS[0] += r.secs
    r.cmd = shown(case.file, sets, np_)
    r.code, r.stdout, r.stderr, r.dir, r.np = p.returncode, p.stdout, p.stderr, out, np_
    if KEEP:
        with open(out + ".log", "w") as f:
            f.write(r.cmd + "\n--- stdout\n" + r.stdout + "\n--- stderr\n" + r.stderr)
    r.hang = r.code in (124, 137)
    r.error_lines = [l for l in r.stderr.splitlines() if l.startswith("error:")]
    r.warnings = [l.strip() for l in r.stdout.splitlines() + r.stderr.splitlines()
                  if l.strip().startswith("warning")]
    r.summary = r.csv = r.u = r.history = None
    r.steps = "-"
    r.problem = None  # unreadable output of a successful run
    if r.code == 0:
        try:
            text = open(os.path.join(out, "summary.json")).read()
            r.summary_text = text
            r.summary = json.loads(text)
            r.steps = r.summary.get("newton", {}).get("steps", "-")
            path = os.path.join(out, "contact_nodes.csv")
            if os.path.exists(path):
                lines = open(path).read().splitlines()
                head = lines[0].split(",")
                r.csv = {}
                for l in lines[1:]:
                    if l.strip():
                        row = dict(zip(head, l.split(",")))
                        r.csv[int(row["node_id"])] = row
            r.history = None
            hpath = os.path.join(out, "history.csv")
            if os.path.exists(hpath):  # a load history: one row per converged load step
                lines = open(hpath).read().splitlines()
                head = lines[0].split(",")
                r.history = [dict(zip(head, l.split(","))) for l in lines[1:] if l.strip()]
            with h5py.File(os.path.join(out, "solution.h5"), "r") as f:
                ids = np.asarray(f["mesh/node_id"][...], dtype=np.int64)
                if "nodal" in f:
                    u = np.asarray(f["nodal/displacement"][...], dtype=np.float64)
                else:  # a load history: the last step's displacement
                    last = max((k for k in f if k.startswith("step_")), key=lambda k: int(k[5:]))
                    u = np.asarray(f[last + "/nodal/displacement"][...], dtype=np.float64)
            order = np.argsort(ids, kind="stable")
            r.ids, r.u = ids[order], u[order]
        except Exception as e:  # noqa: BLE001 - reported as a FAIL row
            r.problem = f"output unreadable: {e}"
    if not KEEP:
        shutil.rmtree(out, ignore_errors=True)
    CACHE[key] = r
    return r


def ref(case, sets=(), np_=1):
    return execute(case, sets, np_)


# ---------------------------------------------------------------------------------------
# Checks. Each returns a list of problems (empty: fine) and a detail string.
def f(row, k):
    return float(row[k])


def finite_problem(r):
    """NaN or inf anywhere in the output."""
    bad = []
    if r.summary is not None and any(w in r.summary_text for w in ("NaN", "Infinity", "nan", "inf")):
        bad.append("summary.json")
    if r.csv is not None:
        for row in r.csv.values():
            for k, v in row.items():
                if k not in ("state", "tangential") and not math.isfinite(float(v)):
                    bad.append("contact_nodes.csv")
                    break
            else:
                continue
            break
    if r.u is not None and not np.all(np.isfinite(r.u)):
        bad.append("solution.h5 displacement")
    return bad


def certificate(r, case, young, tol):
    """Independent KKT / Tresca certificate of a converged run from its own output."""
    if r.csv is None:
        return [], ""
    rows = list(r.csv.values())
    dim = 3 if "z" in rows[0] else 2
    tk = [f"lambda_t{i}" for i in range(1, dim)]
    uk = [f"u_t{i}" for i in range(1, dim)]
    L = max(float(np.abs(r.u).max()), max(abs(f(x, "gap0")) for x in rows), 1e-300)
    wmax = max(f(x, "weight") for x in rows)
    F = max([abs(f(x, "lambda_n")) for x in rows] + [abs(f(x, k)) for x in rows for k in tk] +
            [f(x, "bound") for x in rows] + [young * L * wmax])
    worst = {}

    def note(name, v):
        worst[name] = max(worst.get(name, 0.0), v)

    for x in rows:
        gap, ln = f(x, "gap"), f(x, "lambda_n")
        lt = np.array([f(x, k) for k in tk])
        ut = np.array([f(x, k) for k in uk])
        note("penetration", -gap / L)
        note("lambda_n>0", ln / F)
        if x["state"] == "active":
            note("active gap", abs(gap) / L)
        elif x["state"] == "inactive":
            note("inactive lambda_n", abs(ln) / F)
        else:
            note(f"state {x['state']}", 1.0)
        if case.tresca is None:
            note("lambda_t", float(np.linalg.norm(lt)) / F)
        else:
            b = f(x, "bound")
            note("|lambda_t|>b", (float(np.linalg.norm(lt)) - b) / F)
            if x["tangential"] == "stick":
                note("stick u_t", float(np.linalg.norm(ut)) / L)
            elif x["tangential"] == "slip":
                note("slip |lambda_t|-b", abs(float(np.linalg.norm(lt)) - b) / F)
                nu, nl = float(np.linalg.norm(ut)), float(np.linalg.norm(lt))
                # (no direction to test where lambda_t vanishes: b = 0, e.g. Coulomb off contact)
                if nu > tol * L and nl > tol * F:
                    note("slip alignment", 1.0 - float(lt @ ut) / (nu * nl))
    bad = [f"{k} {v:.1e}" for k, v in worst.items() if v > tol]
    return bad, f"cert {max(worst.values()):.0e}"


def reldiff(a, b):
    s = float(np.abs(b).max())
    d = float(np.abs(a - b).max())
    return d / s if s > 0 else d


def on_threshold_everywhere(r, rel=1e-8):
    """Tresca/Coulomb: every contact node's |lambda_t| equals its bound b > 0. On a body
    whose tangential rigid translation only friction holds (a free body), the total
    tangential load is then a sum of +-b_k, and every translation that keeps the slip
    directions is a solution too: u is unique only up to that translation, and the stick/slip
    labels of the nodes that happen to have u_t = 0 are not unique either."""
    if r.csv is None:
        return False
    rows = list(r.csv.values())
    tk = [k for k in rows[0] if k.startswith("lambda_t")]
    for x in rows:
        b = f(x, "bound")
        lt = math.sqrt(sum(f(x, k) ** 2 for k in tk))
        if not (b > 0 and abs(lt - b) <= rel * b):
            return False
    return True


def compare(r, rr, u_factor=1.0, f_factor=1.0, tol=1e-10, what="ref", sets=True,
            shift=None, ftol=None, translation_if_degenerate=False):
    """The run's answer against a reference run's, scaled: u = u_factor u_ref (+ shift),
    total force = f_factor F_ref (to ftol, default tol), same active set.
    translation_if_degenerate: where the reference has every contact node on its friction
    threshold (on_threshold_everywhere), u is compared modulo a rigid translation and the
    stick/slip labels are not compared (the solution set is an interval of translations)."""
    ftol = tol if ftol is None else ftol
    if rr.code != 0 or rr.u is None:
        return [f"reference ({what}) failed: exit {rr.code} {first_words(rr)}"], ""
    bad = []
    det = []
    degenerate = translation_if_degenerate and on_threshold_everywhere(rr)
    if degenerate:
        det.append("degenerate (all |lambda_t| = b):")
    if r.csv is not None and sets:
        if sorted(r.csv) != sorted(rr.csv):
            bad.append("contact node ids differ")
        else:
            ds = [k for k in r.csv if r.csv[k]["state"] != rr.csv[k]["state"]]
            dt = [k for k in r.csv if r.csv[k].get("tangential") != rr.csv[k].get("tangential")]
            if degenerate:
                dt = []
            if ds:
                bad.append(f"active set differs at {len(ds)} node(s) (ids {ds[:5]})")
            if dt:
                bad.append(f"stick/slip differs at {len(dt)} node(s) (ids {dt[:5]})")
            if not ds and not dt:
                det.append("set =")
    if not np.array_equal(r.ids, rr.ids):
        bad.append("node ids differ")
        return bad, ""
    target = u_factor * rr.u
    if shift is not None:
        target = target + np.asarray(shift)
    if degenerate:
        move = (r.u - target).mean(axis=0)
        target = target + move
        det.append(f"translation {float(np.abs(move).max()) / float(np.abs(rr.u).max()):.0e},")
    du = reldiff(r.u, target)
    det.append(f"u {du:.0e}")
    if du > tol:
        bad.append(f"u differs by {du:.1e} (> {tol:.0e}) of its size")
    if r.csv is not None and rr.csv is not None:
        F = np.array(r.summary["contact"]["total_force"])
        Fr = f_factor * np.array(rr.summary["contact"]["total_force"])
        nf = float(np.linalg.norm(Fr))
        if nf > 0 and rr.summary["contact"]["active_count"] > 0:
            dF = float(np.linalg.norm(F - Fr)) / nf
            det.append(f"F {dF:.0e}")
            if dF > ftol:
                bad.append(f"total force differs by {dF:.1e}")
            pm, pr = r.summary["contact"]["max_pressure"], f_factor * rr.summary["contact"]["max_pressure"]
            if abs(pm - pr) > ftol * abs(pr):
                bad.append(f"p_max {pm:.6e} vs {pr:.6e}")
        if sets and r.summary["contact"]["active_count"] != rr.summary["contact"]["active_count"]:
            bad.append(f"|A| {r.summary['contact']['active_count']} vs "
                       f"{rr.summary['contact']['active_count']}")
    return bad, " ".join(det) + f" vs {what}"


def first_words(r, n=9):
    if r.error_lines:
        return " ".join(r.error_lines[0][len("error:"):].split()[:n])
    tail = (r.stderr.strip().splitlines() or ["(no stderr)"])[-1]
    return tail[:80]

# ---------------------------------------------------------------------------------------
# The checks a row names (scripts/stress.toml): each returns a function of the run giving a
# list of problems (empty: fine) and a detail string.
def against(row_case, case=None, sets=(), ranks=1, what="ref", states=True, translation=False,
            **kw):
    """The answer equals that of `case` (default the row's) run with `sets` on `ranks` ranks."""
    other = row_case if case is None else CASES[case]
    return lambda r: compare(r, execute(other, sets, ranks), what=what, sets=states,
                             translation_if_degenerate=translation, **kw)


def exact_block(row_case, p=0.1, tol=1e-10):
    """All contact nodes active with pressure p (the blocks' exact solution), relative to `tol`
    (round-off of f − A u: grows with A's conditioning)."""
    def check(r):
        rows = list(r.csv.values())
        bad = []
        na = sum(x["state"] == "active" for x in rows)
        if na != len(rows):
            bad.append(f"{len(rows) - na} node(s) not active")
        ps = np.array([f(x, "pressure") for x in rows])
        dp = float(np.abs(ps - p).max()) / p
        if dp > tol:
            bad.append(f"pressure differs from p by {dp:.1e}")
        return bad, f"all active, p = {p} to {dp:.0e}"
    return check


def exact_pulled(row_case):
    """u = (0, 0.01) everywhere, no node active."""
    def check(r):
        bad = []
        na = sum(x["state"] == "active" for x in r.csv.values())
        if na:
            bad.append(f"{na} node(s) active")
        target = np.zeros_like(r.u)
        target[:, 1] = 0.01
        du = reldiff(r.u, target)
        if du > 1e-10:
            bad.append(f"u differs from (0, 0.01) by {du:.1e}")
        return bad, f"none active, u = (0, 0.01) to {du:.0e}"
    return check


def free_force(case):
    """A free body's contact carries its whole load: F = F_ref."""
    def check(r):
        rr = ref(case)
        F = np.array(r.summary["contact"]["total_force"])
        Fr = np.array(rr.summary["contact"]["total_force"])
        dF = float(np.linalg.norm(F - Fr) / np.linalg.norm(Fr))
        return ([f"total force differs from the load by {dF:.1e}"] if dF > 1e-10 else []), \
            f"F = load to {dF:.0e}"
    return check


def c_default(case):
    """E / h_c of the reference run, the unit of the c family's factors (h_c from the contact
    weights, as the solver computes it; the solver's default c is 100 E h_c^(d-2))."""
    rr = ref(case)
    if rr.csv is None:
        return None
    rows = list(rr.csv.values())
    dim = 3 if "z" in rows[0] else 2
    h = np.mean([f(x, "weight") ** (1.0 / (dim - 1)) for x in rows])
    return case.young / h


def hertz_load(case, a, low, low_sets):
    """Loads on the Hertz disk: total force = a x the reference's; u / a = u(low) / low when
    the active set is that of load x low and every active node has gap0 = 0."""
    def check(r):
        rr = ref(case)
        bad, det = [], []
        F = np.array(r.summary["contact"]["total_force"])
        Fr = a * np.array(rr.summary["contact"]["total_force"])
        dF = float(np.linalg.norm(F - Fr) / np.linalg.norm(Fr))
        det.append(f"F = {a:g} F_ref to {dF:.0e}")
        if dF > 1e-10:
            bad.append(f"total force differs from {a:g} x the reference's by {dF:.1e}")
        hc = case.young / c_default(case)
        det.append(f"|u|/h_c {np.abs(r.u).max() / hc:.0e}")
        act = sorted(k for k, x in r.csv.items() if x["state"] == "active")
        det.append(f"|A| {len(act)}")
        if a != low:
            r0 = execute(case, low_sets, 1)
            act0 = sorted(k for k, x in (r0.csv or {}).items() if x["state"] == "active")
            if r0.code == 0 and act == act0 and all(f(r.csv[k], "gap0") == 0.0 for k in act):
                du = reldiff(r.u / a, r0.u / low)
                det.append(f"u/a = u(1e-6)/1e-6 to {du:.0e}")
                if du > 1e-10:
                    bad.append(f"u / a differs from u(1e-6) / 1e-6 by {du:.1e} with the same set")
            elif r0.code == 0 and not set(act0) <= set(act):
                det.append("NOTE: set at x1e-6 not contained")
        return bad, ", ".join(det)
    return check


def tresca_force(case, t):
    """The free disk carries its load: F_y = the reference's, F_x = t / 0.001 x the reference's."""
    def check(r):
        rr = ref(case)
        F = np.array(r.summary["contact"]["total_force"])
        Fr = np.array(rr.summary["contact"]["total_force"]) * np.array([t / 0.001, 1.0])
        dF = float(np.linalg.norm(F - Fr) / np.linalg.norm(Fr))
        return ([f"total force differs from the load by {dF:.1e}"] if dF > 1e-10 else []), \
            f"F = load to {dF:.0e}"
    return check


CHECKS = {"against": against, "exact_block": exact_block, "exact_pulled": exact_pulled,
          "free_force": free_force, "hertz_load": hertz_load, "tresca_force": tresca_force}


def both(checks):
    def check(r):
        bad, det = [], []
        for c in checks:
            b, d = c(r)
            bad += b
            det.append(d)
        return bad, ", ".join(det)
    return check


def check_of(row, case):
    """The row's checks as one function (None: only the certificate)."""
    descs = row.get("check")
    if not descs:
        return None
    fns = []
    for d in descs:
        d = dict(d)
        kind = d.pop("kind")
        if kind not in CHECKS:
            print(f"stress: error: {DATA}: unknown check kind {kind!r}", file=sys.stderr)
            sys.exit(2)
        fns.append(CHECKS[kind](case, **d))
    return fns[0] if len(fns) == 1 else both(fns)


# ---------------------------------------------------------------------------------------
# Rows
SPECS = []


def in_set(row):
    """The row is in this set of the suite (--quick or the full one)."""
    quick = row.get("quick", False)
    return bool(quick) if QUICK else quick != "only"


def spec_of(row):
    """One row as the judge reads it; a "c" row's newton.c from its case's reference run."""
    case = CASES[row["case"]]
    sets = list(row.get("sets", []))
    if "c_factor" in row:
        fac = row["c_factor"]
        sets.append(f"newton.c={fac!r}*E/h_c" if LIST else f"newton.c={tval(fac * c_default(case))}")
    return dict(family=row["family"], case=case, var=row["var"], np=row["ranks"], sets=sets,
                expect=row.get("expect", "ok"), check=check_of(row, case),
                tol=row.get("tol", 1e-8), young=row.get("young", case.young),
                warn=row.get("warn"))


for row in ROW_DATA:
    if not in_set(row):
        continue
    if not (ONLY and row["family"] not in ONLY):
        SPECS.append(spec_of(row))
    elif "c_factor" in row and not LIST:
        c_default(CASES[row["case"]])  # the reference runs do not depend on --only

if LIST:
    for s in SPECS:
        print("\t".join([s["family"], s["case"].name, s["var"], str(s["np"]), s["expect"],
                         shown(s["case"].file, tuple(s["case"].sets) + tuple(s["sets"]), s["np"])]))
    sys.exit(0)




def judge(s):
    case = s["case"]
    r = execute(case, s["sets"], s["np"])
    out = dict(family=s["family"], case=case.name, var=s["var"], np=s["np"],
               steps=r.steps, secs=r.secs, cmd=r.cmd)
    text = r.stdout + r.stderr

    def fail(msg):
        out.update(outcome="FAIL", detail=msg)
        return out

    if r.hang:
        return fail(f"hang: killed after {LIMIT} s")
    if "panicked" in text or "stack backtrace" in text:
        return fail("panic: " + next(l for l in text.splitlines() if "panicked" in l or "backtrace" in l)[:100])
    if r.code not in (0, 1, 2):
        return fail(f"crash: exit {r.code}: {first_words(r)}")
    if r.code != 0:
        if not r.error_lines:
            return fail(f"exit {r.code} without an 'error:' line: {first_words(r)}")
        if len(set(r.error_lines)) > 1:
            return fail(f"exit {r.code} with {len(set(r.error_lines))} different error lines")
        if os.path.exists(r.dir) and not KEEP:
            return fail(f"exit {r.code} left an output directory")
        if s["expect"] == "ok":
            return fail(f"false diagnosis: exit {r.code}: {first_words(r)}")
        out.update(outcome="diag", detail=f"exit {r.code}: {first_words(r)}")
        return out
    if r.problem:
        return fail(r.problem)
    bad = finite_problem(r)
    if bad:
        return fail("NaN/inf in " + ", ".join(bad))
    if r.summary.get("newton") is not None and r.summary["newton"].get("converged") is not True:
        return fail("exit 0 but newton.converged is not true")
    problems, details = [], []
    if s["warn"] is not None:
        has = any("poisson" in w for w in r.warnings)
        if has != s["warn"]:
            problems.append("near-incompressibility warning " + ("missing" if s["warn"] else "unexpected"))
    if r.history is not None:
        # A load history: friction acts on the increment since the previous step, so the
        # certificate of every step is the solver's own per-step columns of history.csv
        # (KKT and friction, each the worst relative violation; docs/friction.md), and the
        # history must be complete.
        cb, worst = [], 0.0
        if r.summary.get("load", {}).get("completed") is not True:
            cb.append("load.completed is not true")
        for row in r.history:
            for k in ("kkt_violation", "friction_violation"):
                v = float(row[k]) if row.get(k) not in (None, "") else 0.0
                worst = max(worst, v)
                if not v <= s["tol"]:
                    cb.append(f"step {row['step']} {k} {v:.1e}")
        cd = f"{len(r.history)} steps, cert {worst:.0e}"
    else:
        cb, cd = certificate(r, case, s["young"], s["tol"])
    problems += cb
    if s["check"] is not None:
        b, d = s["check"](r)
        problems += b
        details.append(d)
    if cd:
        details.append(cd)
    other = [w for w in r.warnings if "poisson" not in w]
    if other:
        details.append("WARNING " + other[0][:60])
    if s["expect"] == "diag":
        return fail("converged where no equilibrium exists: " + "; ".join(problems + details))
    if s["expect"] == "either":
        # A refused reference leaves nothing to compare with; the certificate still holds.
        notes = [p for p in problems if p.startswith("reference (")]
        problems = [p for p in problems if not p.startswith("reference (")]
        details += ["NOTE " + n for n in notes]
    if problems:
        return fail("wrong answer: " + "; ".join(problems) + " (" + ", ".join(details) + ")")
    out.update(outcome="ok", detail=", ".join(x for x in details if x))
    return out
# ---------------------------------------------------------------------------------------
def row_md(o):
    return (f"| {o['case']} | {o['var']} | {o['np']} | {o['outcome']} | {o['steps']} | "
            f"{o['secs']:.1f} | {o['detail']} |")


HEAD = "| case | variation | ranks | outcome | steps | s | detail |\n|---|---|---|---|---|---|---|"
t_start = time.time()
print(f"stress: {len(SPECS)} runs{' (--quick)' if QUICK else ''}, time limit {LIMIT} s per run",
      flush=True)
results = []
fam = None
for s in SPECS:
    if s["family"] != fam:
        fam = s["family"]
        print(f"\n#### {fam}\n\n{HEAD}", flush=True)
    o = judge(s)
    results.append(o)
    print(row_md(o), flush=True)
wall = time.time() - t_start

counts = OrderedDict()
for o in results:
    c = counts.setdefault(o["family"], {"ok": 0, "diag": 0, "FAIL": 0})
    c[o["outcome"]] += 1
tot = {k: sum(c[k] for c in counts.values()) for k in ("ok", "diag", "FAIL")}
summary = ["| family | runs | ok | diag | FAIL |", "|---|---|---|---|---|"]
for k, c in counts.items():
    summary.append(f"| {k} | {sum(c.values())} | {c['ok']} | {c['diag']} | {c['FAIL']} |")
summary.append(f"| **all** | {len(results)} | {tot['ok']} | {tot['diag']} | {tot['FAIL']} |")
extra_runs = COUNTER[0] - len(results)
foot = (f"{len(results)} rows ({COUNTER[0]} solver runs including {extra_runs} reference runs "
        f"that are no row of their own), wall {wall:.0f} s, solver runs {TOTAL_RUN_SECONDS[0]:.0f} s")
print("\n" + "\n".join(summary) + "\n\n" + foot)
fails = [o for o in results if o["outcome"] == "FAIL"]
if fails:
    print("\nFAIL rows, each with its command:")
    for o in fails:
        print(f"- {o['case']} / {o['var']} / {o['np']} ranks: {o['detail']}\n  {o['cmd']}")
if MD:
    with open(MD, "w") as fh:
        fh.write("# Stress suite\n\n`scripts/stress" + (" --quick" if QUICK else "") +
                 f" --md {MD}` — outcomes, tolerances and what is compared: see the header "
                 "of scripts/stress.\n\n" + "\n".join(summary) + "\n\n" + foot + "\n")
        fam = None
        for o in results:
            if o["family"] != fam:
                fam = o["family"]
                fh.write(f"\n## {fam}\n\n{HEAD}\n")
            fh.write(row_md(o) + "\n")
        if fails:
            fh.write("\n## FAIL rows and their commands\n\n")
            for o in fails:
                fh.write(f"- {o['case']} / {o['var']} / {o['np']} ranks: {o['detail']}\n"
                         f"  `{o['cmd']}`\n")
if not KEEP:
    shutil.rmtree(WORK, ignore_errors=True)
sys.exit(1 if fails else 0)
