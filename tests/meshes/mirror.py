"""Mirrors a mesh of a symmetric body part into the whole body, node for node, so that a case
on the part with mirror-plane Dirichlet data can be compared with the same case on the whole
(tests/symmetry.rs). Reads MSH 4.1 (meshio), writes MSH 4.1 ASCII.

    python3 mirror.py PART.msh WHOLE.msh AXES KEEP

AXES: the mirror planes x = 0 / y = 0 / z = 0 as a string of axis letters ("x", "xy");
KEEP: comma list of the boundary groups to keep (mirrored with their cells); every group of
the mesh's own dimension is kept. Nodes on a mirror plane are shared, every other node and cell
gets its mirror image."""
import sys

import meshio
import numpy as np

src, dst, axes, keep = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split(",")
m = meshio.read(src)
dim = 3 if "tetra" in m.cells_dict else 2
cell_type = {3: ("tetra", "triangle"), 2: ("triangle", "line")}[dim]
names = {(v[1], v[0]): k for k, v in m.field_data.items()}
points = m.points.copy()
groups = {}
for block, tags in zip(m.cells, m.cell_data["gmsh:physical"]):
    if block.type not in cell_type:
        continue
    d = dim if block.type == cell_type[0] else dim - 1
    for cell, tag in zip(block.data, tags):
        name = names[(d, tag)]
        if d == dim or name in keep:
            groups.setdefault(name, (d, []))[1].append(cell)
groups = {k: (d, np.array(c)) for k, (d, c) in groups.items()}
for axis in ("xyz".index(a) for a in axes):
    on = np.abs(points[:, axis]) < 1e-12
    image = np.arange(len(points))
    off = np.where(~on)[0]
    image[off] = len(points) + np.arange(len(off))
    mirrored = points[off].copy()
    mirrored[:, axis] *= -1.0
    points = np.vstack([points, mirrored])
    groups = {k: (d, np.vstack([c, image[c]])) for k, (d, c) in groups.items()}
order = sorted(groups, key=lambda k: groups[k][0])
gmsh_type = {(3, 3): 4, (3, 2): 2, (2, 2): 2, (2, 1): 1}
with open(dst, "w") as f:
    f.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n%d\n" % len(order))
    for i, g in enumerate(order):
        f.write('%d %d "%s"\n' % (groups[g][0], i + 1, g))
    f.write("$EndPhysicalNames\n$Entities\n")
    counts = [sum(1 for g in order if groups[g][0] == d) for d in range(4)]
    f.write("%d %d %d %d\n" % tuple(counts))
    lo, hi = points.min(axis=0), points.max(axis=0)
    for i, g in enumerate(order):
        f.write("%d %r %r %r %r %r %r 1 %d 0\n" % (i + 1, *lo, *hi, i + 1))
    f.write("$EndEntities\n")
    n = len(points)
    top = next(i for i, g in enumerate(order) if groups[g][0] == dim) + 1
    f.write("$Nodes\n1 %d 1 %d\n%d %d 0 %d\n" % (n, n, dim, top, n))
    f.write("".join("%d\n" % (i + 1) for i in range(n)))
    f.write("".join("%r %r %r\n" % tuple(p) for p in points))
    f.write("$EndNodes\n")
    total = sum(len(groups[g][1]) for g in order)
    f.write("$Elements\n%d %d 1 %d\n" % (len(order), total, total))
    tag = 1
    for i, g in enumerate(order):
        d, cells = groups[g]
        f.write("%d %d %d %d\n" % (d, i + 1, gmsh_type[(dim, d)], len(cells)))
        for c in cells:
            f.write(" ".join(str(v) for v in [tag, *(c + 1)]) + "\n")
            tag += 1
    f.write("$EndElements\n")
