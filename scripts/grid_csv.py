#!/usr/bin/env python3
"""Write the module grid of tensolve's `[grid]` (docs/method.md §2) as `[structure]` tables.

    scripts/grid_csv.py OUTDIR [--modules NX NY] [--length L] [--height H] [--prestress P]
                              [--braced] [--shear S] [--tilt T] [--groups]

Writes OUTDIR/nodes.csv (node,x,y,z) and OUTDIR/members.csv
(member,a,b,kind,young,section,prestress) with the grid generator's node numbering and member
order, so that the tables, clamped like the grid, give the grid's answers to round-off.
Defaults: the paper's case (16 x 16 standard modules of 1 m x 0.5 m, p = 2000 N, cables
E = 1e11 Pa, S = 0.5e-4 m², bars E = 2e11 Pa, S = 2.8e-4 m²). With --groups, a last column
`group` names each member's kind (lower, upper, bracing, bar, diagonal): the groups of
`prestress.from = "design"` (give --prestress 0 for a table the design fills).
"""
import argparse
import math
import os


def generate(nx, ny, length, height, braced):
    corner = lambda i, j: j * (nx + 1) + i
    x_mid = lambda i, j: (nx + 1) * (ny + 1) + j * nx + i
    y_mid = lambda i, j: (nx + 1) * (ny + 1) + nx * (ny + 1) + j * (nx + 1) + i
    n_nodes = (nx + 1) * (ny + 1) + nx * (ny + 1) + (nx + 1) * ny
    nodes = [None] * n_nodes
    for j in range(ny + 1):
        for i in range(nx + 1):
            nodes[corner(i, j)] = (i * length, j * length, 0.0)
    for j in range(ny + 1):
        for i in range(nx):
            nodes[x_mid(i, j)] = ((i + 0.5) * length, j * length, height)
    for j in range(ny):
        for i in range(nx + 1):
            nodes[y_mid(i, j)] = (i * length, (j + 0.5) * length, height)
    links = []
    for j in range(ny):
        for i in range(nx):
            c = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)]
            u = [x_mid(i, j), y_mid(i + 1, j), x_mid(i, j + 1), y_mid(i, j)]
            links += [(c[k], c[(k + 1) % 4], "lower") for k in range(4)]
            links += [(u[k], u[(k + 1) % 4], "upper") for k in range(4)]
            links += [(c[k], u[k], "bracing") for k in range(4)]
            links += [(c[k], u[(k + 1) % 4], "bar") for k in range(4)]
            if braced:
                links += [(c[0], c[2], "diagonal"), (c[1], c[3], "diagonal"),
                          (u[0], u[2], "diagonal"), (u[1], u[3], "diagonal")]
    return nodes, links


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--modules", nargs=2, type=int, default=[16, 16])
    ap.add_argument("--length", type=float, default=1.0)
    ap.add_argument("--height", type=float, default=0.5)
    ap.add_argument("--prestress", type=float, default=2000.0)
    ap.add_argument("--braced", action="store_true")
    ap.add_argument("--shear", type=float, default=0.0,
                    help="x += SHEAR * y: parallelogram modules")
    ap.add_argument("--tilt", type=float, default=0.0,
                    help="z += TILT * x: a tilted plane")
    ap.add_argument("--groups", action="store_true",
                    help="a last column `group`: the member's kind in its module")
    a = ap.parse_args()
    nodes, links = generate(a.modules[0], a.modules[1], a.length, a.height, a.braced)
    # An affine map keeps the prestress self-balanced when the force densities t0/length are
    # kept: sum q (x_b - x_a) = 0 is linear in the positions.
    if a.shear or a.tilt:
        nodes = [(x + a.shear * y, y, z + a.tilt * x) for (x, y, z) in nodes]
    os.makedirs(a.outdir, exist_ok=True)
    with open(os.path.join(a.outdir, "nodes.csv"), "w") as f:
        f.write("node,x,y,z\n")
        for n, p in enumerate(nodes):
            f.write(f"{n},{p[0]!r},{p[1]!r},{p[2]!r}\n")
    p, l = a.prestress, a.length
    # docs/method.md §2: force densities p/L (lower), 2p/L (upper, bracing), -2p/L (bars), 0 (diagonals);
    # t0 = density * length, computed as tensolve's grid generator does.
    density = {"lower": p / l, "upper": 2.0 * p / l, "bracing": 2.0 * p / l,
               "bar": -2.0 * p / l, "diagonal": 0.0}
    with open(os.path.join(a.outdir, "members.csv"), "w") as f:
        f.write("member,a,b,kind,young,section,prestress" + (",group\n" if a.groups else "\n"))
        for m, (i, j, kind) in enumerate(links):
            xa, xb = nodes[i], nodes[j]
            d = [xb[k] - xa[k] for k in range(3)]
            length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
            young, section = (2e11, 2.8e-4) if kind == "bar" else (1e11, 0.5e-4)
            t0 = density[kind] * length
            group = f",{kind}" if a.groups else ""
            f.write(f"{m},{i},{j},{'bar' if kind == 'bar' else 'cable'},{young!r},{section!r},{t0!r}{group}\n")


if __name__ == "__main__":
    main()
