#!/usr/bin/python3
"""Error against time for every contact method of one or more tables of scripts/bench-contact.

  bench/contact/plot_md.py OUT.png TABLE.md [TABLE.md ...]

Reads the markdown tables scripts/bench-contact writes (bench/results/*.md) and draws, per
method, |p_max error| against Hertz over the solve time, one point per Hertz level (labelled, joined in level
order; the errors as the tables print them, to 0.01 %),
with the linear solves (contact clamped) as vertical ticks at their times: a contact solve left
of its level's tick costs less than one linear solve of the same mesh.
"""

import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(paths):
    out = []
    for p in paths:
        for line in open(p):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) < 11 or not cells[0].startswith("Hertz L"):
                continue
            err = cells[10].replace("%", "").strip()
            out.append({
                "level": cells[0].split()[-1],
                "method": re.sub(r"\*", "", cells[2]),
                "t": float(cells[6]),
                "err": abs(float(err)) / 100 if err else None,
            })
    return out


def main():
    out, tables = sys.argv[1], sys.argv[2:]
    data = rows(tables)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name in sorted({r["method"] for r in data if r["err"] is not None}):
        pts = sorted(((r["t"], r["err"], r["level"]) for r in data
                      if r["method"] == name and r["err"] is not None),
                     key=lambda p: int(p[2][1:]))
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=name)
        if "default" in name:
            for t, e, lv in pts:
                ax.annotate(lv, (t, e), textcoords="offset points", xytext=(-4, 6), fontsize=8)
    for r in data:
        if r["method"].startswith("linear"):
            ax.axvline(r["t"], color="grey", lw=0.6, ls=":")
            ax.annotate(f"linear {r['level']}", (r["t"], 1), xycoords=("data", "axes fraction"),
                        rotation=90, fontsize=7, va="top", ha="right", color="grey")
    ax.set_xlabel("solve time [s] (2 ranks)")
    ax.set_ylabel("|p_max error| against Hertz")
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
