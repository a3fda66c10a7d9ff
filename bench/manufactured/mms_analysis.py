"""The manufactured contact solution of cases/manufactured/contact2d.toml and the errors of a
solver run against it (scripts/bench-manufactured, tests/manufactured.rs).

  /usr/bin/python3 bench/manufactured/mms_analysis.py            self-check (the case's body
                                                                  force against -div σ(u*) by
                                                                  finite differences)
  /usr/bin/python3 bench/manufactured/mms_analysis.py OUT_DIR     the errors of a run, as JSON

u*(x, y) = (0, c + q(x) φ(y)), q(x) = -Q max(a² - x², 0)³, φ(y) = y (1 - y), plane strain.
Errors (relative; u_h the P1 interpolant of the nodal displacement, its gradient constant per
cell; integrals by the 7-point degree-5 rule per triangle):
  h1        |u_h - u*|_H1 / |u*|_H1   (seminorms)
  l2        ‖u_h - u*‖_L2 / ‖u*‖_L2
  pressure  sqrt(Σ w_k (p_k - p*(x_k))²) / sqrt(Σ w_k p*(x_k)²) over the contact nodes
            (p_k = -λ_n^k / w_k, the solver's nodal pressure, w_k its node weight)
  zone      the largest distance ||x_k| - a| of a contact node on the wrong side of the edge of
            the contact zone (active with |x_k| > a, or inactive with |x_k| < a); 0 when every
            node is on its side
"""

import json
import math
import sys
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent.parent
CASE = ROOT / "cases" / "manufactured" / "contact2d.toml"

# The parameters of cases/manufactured/contact2d.toml.
YOUNG, POISSON = 1.0, 0.3
C = -0.01  # rigid push
A = 0.45  # half width of the contact zone
Q = 1.0  # amplitude of q
LAM = YOUNG * POISSON / ((1 + POISSON) * (1 - 2 * POISSON))
MU = YOUNG / (2 * (1 + POISSON))

# Dunavant's 7-point rule, degree 5: barycentric coordinates, weights (sum 1).
_A1, _B1 = 0.059715871789770, 0.470142064105115
_A2, _B2 = 0.797426985353087, 0.101286507323456
_W0, _W1, _W2 = 0.225, 0.132394152788506, 0.125939180544827
RULE_BARY = np.array([[1 / 3, 1 / 3, 1 / 3],
                      [_A1, _B1, _B1], [_B1, _A1, _B1], [_B1, _B1, _A1],
                      [_A2, _B2, _B2], [_B2, _A2, _B2], [_B2, _B2, _A2]])
RULE_W = np.array([_W0, _W1, _W1, _W1, _W2, _W2, _W2])


def _m(x):
    return np.maximum(A * A - x * x, 0.0)


def q(x):
    return -Q * _m(x) ** 3


def dq(x):
    return 6 * Q * x * _m(x) ** 2


def displacement(x, y):
    """u*(x, y) = (0, c + q(x) y (1 - y)) (arrays)."""
    return np.zeros_like(x), C + q(x) * y * (1 - y)


def gradient(x, y):
    """∇u*: (∂x u_x, ∂y u_x, ∂x u_y, ∂y u_y)."""
    z = np.zeros_like(x)
    return z, z, dq(x) * y * (1 - y), q(x) * (1 - 2 * y)


def pressure(x):
    """p*(x) = -σ_yy(x, 0) = -(λ + 2μ) q(x) ≥ 0."""
    return -(LAM + 2 * MU) * q(x)


def body_force(x, y):
    """f = -div σ(u*): f_x = -(λ + μ) q' φ', f_y = -μ q'' φ - (λ + 2μ) q φ''."""
    m = _m(x)
    fx = -6 * (LAM + MU) * Q * x * m ** 2 * (1 - 2 * y)
    fy = -6 * MU * Q * m * (A * A - 5 * x * x) * y * (1 - y) - 2 * (LAM + 2 * MU) * Q * m ** 3
    return fx, fy


def fd_body_force(x, y, h=1e-4):
    """-div σ(u*) by central differences of σ, itself from central differences of u*."""
    def sigma(x, y, e=1e-6):
        def u(x, y):
            return np.array(displacement(np.array(x), np.array(y)))
        dux = (u(x + e, y) - u(x - e, y)) / (2 * e)
        duy = (u(x, y + e) - u(x, y - e)) / (2 * e)
        exx, eyy, exy = dux[0], duy[1], 0.5 * (duy[0] + dux[1])
        tr = exx + eyy
        return np.array([[LAM * tr + 2 * MU * exx, 2 * MU * exy],
                         [2 * MU * exy, LAM * tr + 2 * MU * eyy]])
    dsx = (sigma(x + h, y) - sigma(x - h, y)) / (2 * h)
    dsy = (sigma(x, y + h) - sigma(x, y - h)) / (2 * h)
    return -(dsx[0, 0] + dsy[0, 1]), -(dsx[1, 0] + dsy[1, 1])


def self_check(points=300, seed=1):
    """The case file's body force expressions (evaluated by Python with its max, ^ → **) and
    body_force() against finite differences of σ(u*); the obstacle of the case against c on the
    zone. Returns the largest relative difference."""
    case = tomllib.loads(CASE.read_text())
    exprs = case["body_force"]["expr"]
    rng = np.random.default_rng(seed)
    scale = max(abs(v) for v in body_force(np.array(0.1), np.array(0.3)))
    worst = 0.0
    for _ in range(points):
        x, y = rng.uniform(-1, 1), rng.uniform(0, 1)
        fd = fd_body_force(x, y)
        mine = body_force(np.array(x), np.array(y))
        in_case = [eval(e.replace("^", "**"), {"max": max, "x": x, "y": y}) for e in exprs]
        for a, b, c in zip(fd, mine, in_case):
            worst = max(worst, abs(a - b) / scale, abs(b - c) / scale)
    h = case["contact"]["obstacle"]["expr"]
    for x in np.linspace(-A, A, 11):
        assert eval(h.replace("^", "**"), {"max": max, "x": x}) == C, "obstacle not flat on the zone"
    return worst


def errors(out_dir):
    """The errors of a run (see the module's documentation) and the mesh sizes."""
    import h5py
    with h5py.File(Path(out_dir) / "solution.h5", "r") as f:
        xyz = f["mesh/geometry"][:, :2]
        tri = f["mesh/topology"][:].astype(np.int64)
        u = f["nodal/displacement"][:, :2]
        cx = f["contact/geometry"][:, 0]
        p = f["contact/pressure"][:].ravel()
        w = f["contact/weight"][:].ravel()
        state = f["contact/state"][:].ravel()
    v = xyz[tri]  # cells x 3 x 2
    d1, d2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    area = 0.5 * np.abs(det)
    # P1 gradients: ∇λ1 = (d2y, -d2x)/det, ∇λ2 = (-d1y, d1x)/det, ∇λ0 = -∇λ1 - ∇λ2.
    g1 = np.stack([d2[:, 1], -d2[:, 0]], axis=1) / det[:, None]
    g2 = np.stack([-d1[:, 1], d1[:, 0]], axis=1) / det[:, None]
    g0 = -g1 - g2
    uc = u[tri]  # cells x 3 x 2
    # grad u_h per cell: G[c, i, j] = ∂_j u_i
    gh = (uc[:, 0, :, None] * g0[:, None, :] + uc[:, 1, :, None] * g1[:, None, :]
          + uc[:, 2, :, None] * g2[:, None, :])
    e_h1 = e_l2 = n_h1 = n_l2 = 0.0
    for b, wq in zip(RULE_BARY, RULE_W):
        px = b[0] * v[:, 0, 0] + b[1] * v[:, 1, 0] + b[2] * v[:, 2, 0]
        py = b[0] * v[:, 0, 1] + b[1] * v[:, 1, 1] + b[2] * v[:, 2, 1]
        uh = b[0] * uc[:, 0] + b[1] * uc[:, 1] + b[2] * uc[:, 2]
        ux, uy = displacement(px, py)
        gxx, gxy, gyx, gyy = gradient(px, py)
        wa = wq * area
        e_l2 += np.sum(wa * ((uh[:, 0] - ux) ** 2 + (uh[:, 1] - uy) ** 2))
        n_l2 += np.sum(wa * (ux ** 2 + uy ** 2))
        e_h1 += np.sum(wa * ((gh[:, 0, 0] - gxx) ** 2 + (gh[:, 0, 1] - gxy) ** 2
                             + (gh[:, 1, 0] - gyx) ** 2 + (gh[:, 1, 1] - gyy) ** 2))
        n_h1 += np.sum(wa * (gxx ** 2 + gxy ** 2 + gyx ** 2 + gyy ** 2))
    ps = pressure(cx)
    active = state > 0.5
    wrong = (active & (np.abs(cx) > A)) | (~active & (np.abs(cx) < A))
    zone = float(np.max(np.abs(np.abs(cx[wrong]) - A))) if wrong.any() else 0.0
    return {
        "cells": int(len(tri)),
        "nodes": int(len(xyz)),
        "h": float(math.sqrt(np.sum(area) / len(tri))),
        "h1": float(math.sqrt(e_h1 / n_h1)),
        "l2": float(math.sqrt(e_l2 / n_l2)),
        "h1_abs": float(math.sqrt(e_h1)),
        "l2_abs": float(math.sqrt(e_l2)),
        "pressure": float(math.sqrt(np.sum(w * (p - ps) ** 2) / np.sum(w * ps ** 2))),
        "zone": zone,
        "wrong_side": int(np.sum(wrong)),
        "active": int(np.sum(active)),
        "active_exact": int(np.sum(np.abs(cx) < A)),
    }


if __name__ == "__main__":
    if len(sys.argv) > 1:
        print("RESULT " + json.dumps(errors(sys.argv[1])))
    else:
        worst = self_check()
        print(f"body force: case and formula against finite differences, max rel. diff {worst:.2e}")
        sys.exit(0 if worst < 1e-5 else 1)
