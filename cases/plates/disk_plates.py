#!/usr/bin/python3
"""The half disk (radius 1, centre at the origin, x >= 0) pressed between two plates, meshed
exactly mirror-symmetric about y = 0: the bottom quarter is meshed by gmsh, the top quarter is
its mirror image (node coordinates (x, -y), the same triangles), so that a symmetric problem
has a symmetric discrete solution to round-off.

Groups: "bottom" (the arc from -90 to -30 degrees) and "top" (30 to 90 degrees), the two
contact arcs, with no node in common; "side" (the free arc from -30 to 30 degrees); "sym" (the
line x = 0); "mid" (the half diameter y = 0, x >= 0; inside the body); "disk" (the surface).
Size hc at the poles (0, -1) and (0, 1), h0 at the centre and on the side.

With --quarter only the bottom quarter is written (the same node tags; "mid" is then its
boundary y = 0): the model of the same problem by its symmetry.

  cases/plates/disk_plates.py OUT.msh [--hc 0.02] [--h0 0.1] [--quarter]
"""

import argparse
import math

import gmsh


def quarter(hc, h0):
    """Meshes the bottom quarter; returns nodes {tag: (x, y)}, triangles [(a, b, c)], and the
    node chains of its curves (bottom arc, side arc, sym line, mid line), each in order."""
    gmsh.model.add("quarter")
    geo = gmsh.model.geo
    a = math.pi / 6
    c = geo.addPoint(0, 0, 0, h0)
    s = geo.addPoint(0, -1, 0, hc)
    p = geo.addPoint(math.cos(a), -math.sin(a), 0, h0)
    e = geo.addPoint(1, 0, 0, h0)
    arc_bottom = geo.addCircleArc(s, c, p)
    arc_side = geo.addCircleArc(p, c, e)
    mid = geo.addLine(e, c)
    sym = geo.addLine(c, s)
    loop = geo.addCurveLoop([arc_bottom, arc_side, mid, sym])
    surf = geo.addPlaneSurface([loop])
    geo.synchronize()
    gmsh.model.mesh.generate(2)
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    nodes = {int(t): (xyz[3 * i], xyz[3 * i + 1]) for i, t in enumerate(tags)}
    _, _, conn = gmsh.model.mesh.getElements(2, surf)
    tri = [tuple(int(v) for v in conn[0][3 * i:3 * i + 3]) for i in range(len(conn[0]) // 3)]

    def chain(curve):
        t, _, _ = gmsh.model.mesh.getNodes(1, curve, includeBoundary=True)
        pts = [int(x) for x in t]
        # includeBoundary puts the end points last: order along the curve by parameter
        first, last = pts[-2], pts[-1]
        return [first] + pts[:-2] + [last]

    return nodes, tri, {
        "bottom": chain(arc_bottom),
        "side": chain(arc_side),
        "sym": chain(sym),
        "mid": chain(mid),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--hc", type=float, default=0.02)
    ap.add_argument("--h0", type=float, default=0.1)
    ap.add_argument("--quarter", action="store_true", help="the bottom quarter only")
    args = ap.parse_args()
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    nodes, tri, chains = quarter(args.hc, args.h0)
    gmsh.model.remove()
    if args.quarter:
        write(args.out, nodes, tri, {k: [v] for k, v in chains.items()})
        return
    # the mirror: nodes off y = 0 get a partner (x, -y); nodes on y = 0 are their own
    on_mid = {t for t, (_, y) in nodes.items() if y == 0.0}
    top = max(nodes) + 1
    partner = {}
    for t in sorted(nodes):
        if t in on_mid:
            partner[t] = t
        else:
            partner[t] = top
            top += 1
    all_nodes = dict(nodes)
    for t, m in partner.items():
        if m != t:
            x, y = nodes[t]
            all_nodes[m] = (x, -y)
    # mirrored triangles keep the counter-clockwise orientation by swapping two vertices
    all_tri = tri + [(partner[a], partner[c], partner[b]) for a, b, c in tri]
    mirror = lambda ch: [partner[t] for t in ch]
    curves = {
        "bottom": [chains["bottom"]],
        "top": [mirror(chains["bottom"])],
        "side": [chains["side"], mirror(chains["side"])],
        "sym": [chains["sym"], mirror(chains["sym"])],
        "mid": [chains["mid"]],
    }
    write(args.out, all_nodes, all_tri, curves)


def write(out, all_nodes, all_tri, curves):
    """Writes the mesh: one discrete surface, one discrete curve per node chain, the groups."""
    gmsh.model.add("disk_plates")
    surf = gmsh.model.addDiscreteEntity(2)
    order = sorted(all_nodes)
    gmsh.model.mesh.addNodes(
        2, surf, order, [c for t in order for c in (*all_nodes[t], 0.0)]
    )
    gmsh.model.mesh.addElementsByType(surf, 2, [], [v for t in all_tri for v in t])
    for name, pieces in curves.items():
        ents = []
        for ch in pieces:
            cu = gmsh.model.addDiscreteEntity(1)
            gmsh.model.mesh.addElementsByType(
                cu, 1, [], [v for i in range(len(ch) - 1) for v in (ch[i], ch[i + 1])]
            )
            ents.append(cu)
        g = gmsh.model.addPhysicalGroup(1, ents)
        gmsh.model.setPhysicalName(1, g, name)
    g = gmsh.model.addPhysicalGroup(2, [surf])
    gmsh.model.setPhysicalName(2, g, "disk")
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.write(out)
    gmsh.finalize()
    print(out)


if __name__ == "__main__":
    main()
