"""Hertz reference values and error measures for scripts/bench-hertz (THEORY.md §6).

Pure functions only (no solver runs), so they can be checked on their own:
    /usr/bin/python3 bench/hertz/hertz_analysis.py      (self-check)
"""

import csv
import math

# The case cases/hertz/hertz.toml: unit disk, plane strain, E = 2, nu = 0.3, normal pressure
# 0.02 on the top eighth (angles 3pi/8 .. 5pi/8).
RADIUS = 1.0
YOUNG = 2.0
POISSON = 0.3
PRESSURE = 0.02
LOAD_ARC = (3.0 * math.pi / 8.0, 5.0 * math.pi / 8.0)


def total_force(pressure=PRESSURE, arc=LOAD_ARC):
    """Vertical resultant of a normal pressure on an arc of the unit circle:
    F = ∫ p sin(a) da = p (cos a0 − cos a1) (THEORY §6)."""
    return pressure * (math.cos(arc[0]) - math.cos(arc[1]))


def hertz(force=None, radius=RADIUS, young=YOUNG, poisson=POISSON):
    """Hertz line contact in plane strain (THEORY §6): E* = E / (1 − nu²),
    b = sqrt(4 F R / (pi E*)), p_max = 2 F / (pi b). Returns (p_max, b)."""
    if force is None:
        force = total_force()
    e_star = young / (1.0 - poisson * poisson)
    b = math.sqrt(4.0 * force * radius / (math.pi * e_star))
    return 2.0 * force / (math.pi * b), b


def hertz_profile(x, p_max, b):
    """p_H(x) = p_max sqrt(1 − x²/b²) for |x| < b, else 0."""
    if abs(x) >= b:
        return 0.0
    return p_max * math.sqrt(1.0 - (x / b) ** 2)


def l2_pressure_error(nodes, p_max, b):
    """Discrete relative L2 error of the pressure profile over the contact nodes:
    sqrt(Σ_k w_k (p_k − p_H(x_k))²) / sqrt(Σ_k w_k p_H(x_k)²).
    `nodes` is an iterable of (x, weight, pressure)."""
    num = den = 0.0
    for x, w, p in nodes:
        ph = hertz_profile(x, p_max, b)
        num += w * (p - ph) ** 2
        den += w * ph * ph
    if den <= 0.0:
        return float("nan")
    return math.sqrt(num / den)


def read_contact_nodes(path):
    """(x, weight, pressure) of every row of a contact_nodes.csv."""
    out = []
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            out.append((float(row["x"]), float(row["weight"]), float(row["pressure"])))
    return out


def rel_err(value, ref):
    """|value − ref| / |ref|, or NaN if value is missing."""
    if value is None:
        return float("nan")
    return abs(value - ref) / abs(ref)


def _self_check():
    f = total_force()
    assert abs(f - 0.015307) < 5e-7, f
    p, b = hertz(f)
    # /work/shared/reference/hertz2d.toml: half_width 0.09417, max_pressure 0.103483
    assert abs(b - 0.09417) < 5e-6, b
    assert abs(p - 0.103483) < 5e-7, p
    # the literal vertical traction (0, -0.02) on the same arc: F = 0.02 * arc length = 0.015708
    pv, bv = hertz(PRESSURE * (LOAD_ARC[1] - LOAD_ARC[0]))
    assert abs(bv - 0.09540) < 5e-5 and abs(pv - 0.10483) < 5e-5, (pv, bv)
    # the exact profile sampled on a fine uniform grid has (near) zero error; a 10 % higher
    # profile has exactly 10 % error; a zero profile has 100 %.
    n = 2001
    h = 0.4 / (n - 1)
    xs = [-0.2 + i * h for i in range(n)]
    exact = [(x, h, hertz_profile(x, p, b)) for x in xs]
    assert l2_pressure_error(exact, p, b) < 1e-12
    up = [(x, w, 1.1 * q) for x, w, q in exact]
    assert abs(l2_pressure_error(up, p, b) - 0.1) < 1e-12
    zero = [(x, w, 0.0) for x, w, _ in exact]
    assert abs(l2_pressure_error(zero, p, b) - 1.0) < 1e-12
    # a profile of the wrong width: clearly nonzero
    wide = [(x, w, hertz_profile(x, p, 1.2 * b)) for x, w, _ in exact]
    assert l2_pressure_error(wide, p, b) > 0.05
    assert hertz_profile(b, p, b) == 0.0 and hertz_profile(0.0, p, b) == p
    print(f"hertz_analysis: ok (F = {f:.6f}, b = {b:.5f}, p_max = {p:.6f})")


if __name__ == "__main__":
    _self_check()
