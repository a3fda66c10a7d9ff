"""The manufactured contact solutions of cases/manufactured/contact{2,3}d.toml and the errors of
a solver run against them (scripts/bench-manufactured, tests/manufactured.rs).

  /usr/bin/python3 bench/manufactured/mms_analysis.py            self-check (the case's body
                                                                  force against -div σ(u*) by
                                                                  finite differences)
  /usr/bin/python3 bench/manufactured/mms_analysis.py OUT_DIR     the errors of a run, as JSON

u*(x, y) = (0, c + q(x) φ(y)), q(x) = -Q max(a² - x², 0)³, φ(y) = y (1 - y), plane strain;
in 3D u* = (0, 0, c + q(x, y) φ(z)), q = -Q max(a² - x² - y², 0)³.
Errors (relative; u_h the P1 interpolant of the nodal displacement, its gradient constant per
cell; integrals per cell by rules of degree 5: Dunavant's 7 points on triangles, a collapsed
4 x 4 x 4 Gauss product on tetrahedra):
  h1        |u_h - u*|_H1 / |u*|_H1   (seminorms)
  l2        ‖u_h - u*‖_L2 / ‖u*‖_L2
  pressure  sqrt(Σ w_k (p_k - p*(x_k))²) / sqrt(Σ w_k p*(x_k)²) over the contact nodes
            (p_k = -λ_n^k / w_k, the solver's nodal pressure, w_k its node weight)
  zone      the largest distance |r_k - a| of a contact node on the wrong side of the edge of
            the contact zone (active with r_k > a, or inactive with r_k < a; r = |x| in 2D,
            sqrt(x² + y²) in 3D); 0 when every node is on its side
  gap0_zone_dev, gap_star_min_outside   the obstacle as the solver projects onto it:
            max |g0 + c| on the zone (0: flat at c, vertical normal), and the smallest
            linearised gap u*·n + g0 of u* outside the zone (> 0: u* is admissible there)
"""

import json
import math
import sys
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent.parent
CASES = {2: ROOT / "cases" / "manufactured" / "contact2d.toml",
         3: ROOT / "cases" / "manufactured" / "contact3d.toml"}

# The parameters of cases/manufactured/contact{2,3}d.toml.
YOUNG, POISSON = 1.0, 0.3
C = -0.01  # rigid push
A = 0.45  # half width (2D) or radius (3D) of the contact zone
Q = 1.0  # amplitude of q
LAM = YOUNG * POISSON / ((1 + POISSON) * (1 - 2 * POISSON))
MU = YOUNG / (2 * (1 + POISSON))

# Triangles: Dunavant's 7-point rule, degree 5 (barycentric coordinates, weights summing to 1).
_A1, _B1 = 0.059715871789770, 0.470142064105115
_A2, _B2 = 0.797426985353087, 0.101286507323456
_W0, _W1, _W2 = 0.225, 0.132394152788506, 0.125939180544827
TRI_BARY = np.array([[1 / 3, 1 / 3, 1 / 3],
                     [_A1, _B1, _B1], [_B1, _A1, _B1], [_B1, _B1, _A1],
                     [_A2, _B2, _B2], [_B2, _A2, _B2], [_B2, _B2, _A2]])
TRI_W = np.array([_W0, _W1, _W1, _W1, _W2, _W2, _W2])


def tet_rule(n=4):
    """Tetrahedra: the collapsed (Duffy) product of n-point Gauss-Legendre rules,
    x = u, y = v (1 - u), z = w (1 - u)(1 - v), Jacobian (1 - u)² (1 - v): exact for degree
    2n - 3 (n = 4: degree 5). Barycentric coordinates and weights summing to 1."""
    g, w = np.polynomial.legendre.leggauss(n)
    g, w = 0.5 * (g + 1), 0.5 * w
    bary, weight = [], []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                u, v, t = g[i], g[j], g[k]
                x, y, z = u, v * (1 - u), t * (1 - u) * (1 - v)
                bary.append([1 - x - y - z, x, y, z])
                weight.append(6 * w[i] * w[j] * w[k] * (1 - u) ** 2 * (1 - v))
    return np.array(bary), np.array(weight)


TET_BARY, TET_W = tet_rule()


def _r2(X):
    """Squared distance from the axis (the horizontal coordinates: all but the last)."""
    return np.sum(X[:, :-1] ** 2, axis=1)


def _m(X):
    return np.maximum(A * A - _r2(X), 0.0)


def displacement(X):
    """u*(X) = (0(, 0), c + q φ(t)), q = -Q m³, φ(t) = t (1 - t), t the last coordinate."""
    t = X[:, -1]
    u = np.zeros_like(X)
    u[:, -1] = C - Q * _m(X) ** 3 * t * (1 - t)
    return u


def gradient(X):
    """∇u*: G[:, i, j] = ∂_j u*_i; only the last row is nonzero: ∂_j q φ, q φ'."""
    n, d = X.shape
    t, m = X[:, -1], _m(X)
    G = np.zeros((n, d, d))
    for j in range(d - 1):
        G[:, -1, j] = 6 * Q * X[:, j] * m ** 2 * t * (1 - t)
    G[:, -1, -1] = -Q * m ** 3 * (1 - 2 * t)
    return G


def pressure(X):
    """p* = -σ_nn on the bottom = (λ + 2μ) Q m³ ≥ 0."""
    return (LAM + 2 * MU) * Q * _m(X) ** 3


def body_force(X):
    """f = -div σ(u*): f_j = -6 (λ + μ) Q x_j m² φ'(t) (horizontal j), and the vertical
    component -μ Δq φ - (λ + 2μ) q φ'' with Δq = 6 Q m (m - 4 x²) (2D) or 12 Q m (m - 2 r²)
    (3D)."""
    n, d = X.shape
    t, m, r2 = X[:, -1], _m(X), _r2(X)
    f = np.zeros_like(X)
    for j in range(d - 1):
        f[:, j] = -6 * (LAM + MU) * Q * X[:, j] * m ** 2 * (1 - 2 * t)
    lap = 6 * Q * m * (m - 4 * r2) if d == 2 else 12 * Q * m * (m - 2 * r2)
    f[:, -1] = -MU * lap * t * (1 - t) - 2 * (LAM + 2 * MU) * Q * m ** 3
    return f


def fd_body_force(X, h=1e-4, e=1e-6):
    """-div σ(u*) by central differences of σ, itself from central differences of u*."""
    n, d = X.shape

    def sigma(Y):
        G = np.zeros((n, d, d))
        for j in range(d):
            dY = np.zeros(d)
            dY[j] = e
            G[:, :, j] = (displacement(Y + dY) - displacement(Y - dY)) / (2 * e)
        eps = 0.5 * (G + G.transpose(0, 2, 1))
        tr = np.trace(eps, axis1=1, axis2=2)
        return LAM * tr[:, None, None] * np.eye(d) + 2 * MU * eps

    div = np.zeros((n, d))
    for j in range(d):
        dX = np.zeros(d)
        dX[j] = h
        div += ((sigma(X + dX) - sigma(X - dX)) / (2 * h))[:, :, j]
    return -div


def self_check(points=200, seed=1):
    """For both cases: their body force expressions (evaluated by Python, ^ → **) and
    body_force() against finite differences of σ(u*); their obstacles flat at c on the zone;
    the quadrature rules exact on monomials of degree 5. Returns the largest relative
    difference."""
    rng = np.random.default_rng(seed)
    worst = 0.0
    for d, path in CASES.items():
        case = tomllib.loads(path.read_text())
        exprs = [e.replace("^", "**") for e in case["body_force"]["expr"]]
        X = np.column_stack([rng.uniform(-1, 1, points) for _ in range(d - 1)]
                            + [rng.uniform(0, 1, points)])
        fd, mine = fd_body_force(X), body_force(X)
        names = "xyz"[:d]
        in_case = np.array([[eval(e, {"max": max, **dict(zip(names, p))}) for e in exprs]
                            for p in X])
        scale = np.abs(mine).max()
        worst = max(worst, np.abs(fd - mine).max() / scale, np.abs(in_case - mine).max() / scale)
        h = case["contact"]["obstacle"]["expr"].replace("^", "**")
        for p in X[_r2(X) < A * A]:
            assert eval(h, {"max": max, **dict(zip(names, p))}) == C, f"{path}: not flat"
    for bary, w, d in ((TRI_BARY, TRI_W, 2), (TET_BARY, TET_W, 3)):
        # ∫ over the unit simplex of x^i y^j (z^k) = i! j! (k!) d! / (i + j (+ k) + d)! (× 1/d!
        # for the measure, here folded in: weights sum to 1, so compare with d! i! j! k! / (…)!)
        for powers in ([5, 0, 0], [2, 3, 0], [1, 2, 2], [0, 1, 4])[: 4]:
            p = powers[:d]
            approx = np.sum(w * np.prod(bary[:, 1:] ** np.array(p), axis=1))
            exact = math.factorial(d) * math.prod(math.factorial(k) for k in p) \
                / math.factorial(sum(p) + d)
            worst = max(worst, abs(approx - exact) / exact)
    return worst


def errors(out_dir):
    """The errors of a run (see the module's documentation) and the mesh sizes."""
    import h5py
    with h5py.File(Path(out_dir) / "solution.h5", "r") as f:
        cells = f["mesh/topology"][:].astype(np.int64)
        d = cells.shape[1] - 1
        xyz = f["mesh/geometry"][:, :d]
        u = f["nodal/displacement"][:, :d]
        cx = f["contact/geometry"][:, :d]
        p = f["contact/pressure"][:].ravel()
        w = f["contact/weight"][:].ravel()
        state = f["contact/state"][:].ravel()
        g0 = f["contact/gap0"][:].ravel()
    # the contact nodes only: a surface node held by Dirichlet data has state -1 and NaN fields
    keep = state != -1
    cx, p, w, state, g0 = cx[keep], p[keep], w[keep], state[keep], g0[keep]
    v = xyz[cells]  # cells x (d+1) x d
    J = np.stack([v[:, k + 1] - v[:, 0] for k in range(d)], axis=2)  # columns: edges
    det = np.linalg.det(J)
    vol = np.abs(det) / math.factorial(d)
    # P1 gradients: rows of J^-1 are ∇λ_1..∇λ_d; ∇λ_0 = -Σ.
    Jinv = np.linalg.inv(J)
    grads = np.concatenate([-Jinv.sum(axis=1, keepdims=True), Jinv], axis=1)  # cells x (d+1) x d
    uc = u[cells]  # cells x (d+1) x d
    gh = np.einsum("cai,caj->cij", uc, grads)  # ∂_j u_i per cell
    bary_all, w_all = (TRI_BARY, TRI_W) if d == 2 else (TET_BARY, TET_W)
    e_h1 = e_l2 = n_h1 = n_l2 = 0.0
    for b, wq in zip(bary_all, w_all):
        X = np.einsum("a,cai->ci", b, v)
        uh = np.einsum("a,cai->ci", b, uc)
        us, gs = displacement(X), gradient(X)
        wv = wq * vol
        e_l2 += np.sum(wv * np.sum((uh - us) ** 2, axis=1))
        n_l2 += np.sum(wv * np.sum(us ** 2, axis=1))
        e_h1 += np.sum(wv * np.sum((gh - gs) ** 2, axis=(1, 2)))
        n_h1 += np.sum(wv * np.sum(gs ** 2, axis=(1, 2)))
    ps = pressure(cx)
    r = np.sqrt(_r2(cx))
    active = state > 0.5
    wrong = (active & (r > A)) | (~active & (r < A))
    zone = float(np.max(np.abs(r[wrong] - A))) if wrong.any() else 0.0
    # The obstacle as the solver sees it: g0 = -c on the zone; outside, u*'s linearised gap
    # u*·n + g0 > 0 (n the graph's unit upward normal, ∇h = -6 max(r² - a², 0)² x_horizontal).
    s = -6 * np.maximum(_r2(cx) - A * A, 0.0) ** 2
    n_up = 1 / np.sqrt(1 + s ** 2 * _r2(cx))
    lin = displacement(cx)[:, -1] * n_up + g0
    inside = r < A
    return {
        "dim": d,
        "cells": int(len(cells)),
        "nodes": int(len(xyz)),
        "h": float((np.sum(vol) / len(cells)) ** (1 / d)),
        "h1": float(math.sqrt(e_h1 / n_h1)),
        "l2": float(math.sqrt(e_l2 / n_l2)),
        "h1_abs": float(math.sqrt(e_h1)),
        "l2_abs": float(math.sqrt(e_l2)),
        "pressure": float(math.sqrt(np.sum(w * (p - ps) ** 2) / np.sum(w * ps ** 2))),
        "zone": zone,
        "wrong_side": int(np.sum(wrong)),
        "active": int(np.sum(active)),
        "active_exact": int(np.sum(r < A)),
        "gap0_zone_dev": float(np.max(np.abs(g0[inside] + C))) if inside.any() else 0.0,
        "gap_star_min_outside": float(np.min(lin[~inside])) if (~inside).any() else 0.0,
    }


if __name__ == "__main__":
    if len(sys.argv) > 1:
        print("RESULT " + json.dumps(errors(sys.argv[1])))
    else:
        worst = self_check()
        print("body force: cases and formula against finite differences, quadrature on "
              f"monomials: max rel. diff {worst:.2e}")
        sys.exit(0 if worst < 1e-5 else 1)
