#!/usr/bin/env python3
"""Write the shipped tensegrity cases (SPEC §8) as `[structure]` cases.

    python3 scripts/tensegrity_cases.py [--out cases]

Writes OUT/<name>.toml with OUT/<name>/nodes.csv and OUT/<name>/members.csv for `simplex`,
`prism4`, `tower`, `saddle-net` and `simplex-no-equilibrium` (the same bytes on every run), and
prints per case the node and member counts, the mechanisms m and self-stress states s of the
equilibrium matrix on the free dofs and the smallest eigenvalue of Mᵀ K_G(t0) M (M an
orthonormal basis of the mechanisms; positive: prestress-stable), or for the no-equilibrium case
the facts that make it one.

Prestress: the structure's single self-stress state (s = 1), the null vector of the equilibrium
matrix on the free dofs (SVD), scaled to a stated member force; on the saddle net the state of
uniform force densities (t = q ℓ), checked to be that null vector. Every state is checked: bars
compressed, cables tensioned, in equilibrium at every free node to 1e-9 of the Σ|t0| met there
(tensolve's test), prestress-stable. Materials: cables E = 1e11 Pa, S = 0.5e-4 m²; bars
E = 2e11 Pa, S = 2.8e-4 m² (tensolve's grid defaults).
"""

import argparse
import math
import os

import numpy as np

CABLE = (1e11, 0.5e-4)
BAR = (2e11, 2.8e-4)
IMBALANCE_RELATIVE = 1e-9


def equilibrium_matrix(X, ends, held):
    """A = Bᵀ on the free dofs: column j is ∇ℓ_j (−n at end a, +n at end b)."""
    index = -np.ones(X.shape, dtype=int)
    index[~held] = np.arange(np.count_nonzero(~held))
    A = np.zeros((np.count_nonzero(~held), len(ends)))
    for j, (a, b) in enumerate(ends):
        n = (X[b] - X[a]) / np.linalg.norm(X[b] - X[a])
        for node, sign in ((a, -1.0), (b, 1.0)):
            rows = index[node]
            A[rows[rows >= 0], j] += sign * n[rows >= 0]
    return A


def counts(A):
    """(rank, m, s, U, Vᵀ) of A = U S Vᵀ, the rank at 1e-10 of the largest singular value."""
    U, S, Vt = np.linalg.svd(A)
    rank = int(np.count_nonzero(S > 1e-10 * S[0]))
    return rank, A.shape[0] - rank, A.shape[1] - rank, U, Vt


def self_stress(X, ends, held, scale_member, scale_force):
    """The single self-stress state (s = 1), scaled so that member `scale_member` carries `scale_force`."""
    _, _, s, _, Vt = counts(equilibrium_matrix(X, ends, held))
    assert s == 1, f"expected one self-stress state, found s = {s}"
    return Vt[-1] * (scale_force / Vt[-1][scale_member])


def prestress_stability(X, ends, held, t):
    """Smallest eigenvalue of Mᵀ K_G(t) M, M an orthonormal basis of the mechanisms (None when m = 0)."""
    rank, m, _, U, _ = counts(equilibrium_matrix(X, ends, held))
    if m == 0:
        return None
    index = -np.ones(X.shape, dtype=int)
    index[~held] = np.arange(np.count_nonzero(~held))
    KG = np.zeros((U.shape[0], U.shape[0]))
    for j, (a, b) in enumerate(ends):
        d = X[b] - X[a]
        length = np.linalg.norm(d)
        n = d / length
        G = t[j] / length * (np.eye(3) - np.outer(n, n))
        for p, sp in ((a, -1.0), (b, 1.0)):
            for q, sq in ((a, -1.0), (b, 1.0)):
                rows, cols = index[p], index[q]
                KG[np.ix_(rows[rows >= 0], cols[cols >= 0])] += sp * sq * G[np.ix_(rows >= 0, cols >= 0)]
    M = U[:, rank:]
    return float(np.linalg.eigvalsh(M.T @ KG @ M)[0])


def check_state(X, ends, held, bar, t):
    """Bars compressed, cables tensioned, Bᵀt = 0 at every free component to 1e-9 of Σ|t| at the node."""
    assert np.all(t[bar] < 0) and np.all(t[~bar] > 0), "a bar in tension or a cable in compression"
    force = np.zeros(X.shape)
    total = np.zeros(len(X))
    for j, (a, b) in enumerate(ends):
        n = (X[b] - X[a]) / np.linalg.norm(X[b] - X[a])
        force[a] += t[j] * n
        force[b] -= t[j] * n
        total[[a, b]] += abs(t[j])
    force[held] = 0.0
    worst = np.max(np.linalg.norm(force, axis=1) / np.maximum(total, 1e-300))
    assert worst <= IMBALANCE_RELATIVE, f"prestress imbalance {worst:.3g} of the Σ|t0| at a node"


def prism(n, radius, height):
    """An n-strut prism: bottom polygon (nodes 0..n−1) at z = 0, top (n..2n−1) at z = height,
    turned by 90° + 180°/n; bar i from bottom i to top i, top ring cable top i to top i+1,
    side cable bottom i to top i−1. Returns the nodes and the members (a, b, bar?)."""
    twist = math.pi / 2 + math.pi / n
    X = np.array([[radius * math.cos(2 * math.pi * i / n), radius * math.sin(2 * math.pi * i / n), 0.0]
                  for i in range(n)]
                 + [[radius * math.cos(2 * math.pi * i / n + twist), radius * math.sin(2 * math.pi * i / n + twist),
                     height] for i in range(n)])
    members = ([(i, n + i, True) for i in range(n)]
               + [(n + i, n + (i + 1) % n, False) for i in range(n)]
               + [(i, n + (i - 1) % n, False) for i in range(n)])
    return X, members


def tower_topology(stages):
    """A Snelson-style tower of 3-strut stages: stage k has bottom nodes B(k, i) = 6k + i and top
    nodes T(k, i) = 6k + 3 + i. Each stage: bars B(k,i)–T(k,i), side cables B(k,i)–T(k,i−1);
    between stages k and k+1: saddle cables B(k+1,i)–T(k,i) and B(k+1,i)–T(k,i+1), a lower tie
    B(k+1,i)–B(k,i+1), an upper tie T(k,i)–T(k+1,i); a top ring on the last stage."""
    B = lambda k, i: 6 * k + i % 3
    T = lambda k, i: 6 * k + 3 + i % 3
    members = []
    for k in range(stages):
        members += [(B(k, i), T(k, i), True) for i in range(3)]
        members += [(B(k, i), T(k, i - 1), False) for i in range(3)]
    members += [(T(stages - 1, i), T(stages - 1, i + 1), False) for i in range(3)]
    for k in range(stages - 1):
        for i in range(3):
            members += [(B(k + 1, i), T(k, i), False), (B(k + 1, i), T(k, i + 1), False),
                        (B(k + 1, i), B(k, i + 1), False), (T(k, i), T(k + 1, i), False)]
    return members


def tower_start(stages, radius, height, rise):
    """Stacked simplex stages (twist 150°) each `rise` above the last and turned 210°: the
    form-finding's starting geometry."""
    X = np.zeros((6 * stages, 3))
    for k in range(stages):
        for i in range(3):
            a = 2 * math.pi * i / 3 + k * math.radians(210.0)
            X[6 * k + i] = [radius * math.cos(a), radius * math.sin(a), k * rise]
            a += math.radians(150.0)
            X[6 * k + 3 + i] = [radius * math.cos(a), radius * math.sin(a), k * rise + height]
    return X


def form_find(X, ends, held, bar, q):
    """Form-finding: a stationary point of ½ Σ_cables q ℓ² with every bar keeping its length (Newton
    on the KKT system from X). There the cables' force density q and the bars' multipliers λ are
    in equilibrium at every free node: a self-stress (t = q ℓ, λ ℓ) of the found geometry."""
    X = X.copy()
    bars = np.flatnonzero(bar)
    lengths = np.linalg.norm(X[ends[bars, 1]] - X[ends[bars, 0]], axis=1)
    free = np.flatnonzero(~held.ravel())

    def density_matrix(density):
        D = np.zeros((len(X), len(X)))
        for (a, b), d in zip(ends, density):
            D[[a, b], [a, b]] += d
            D[a, b] -= d
            D[b, a] -= d
        return np.kron(D, np.eye(3))

    def constraints():
        J = np.zeros((len(bars), X.size))
        d = X[ends[bars, 1]] - X[ends[bars, 0]]
        for r, (a, b) in enumerate(ends[bars]):
            J[r, 3 * b:3 * b + 3], J[r, 3 * a:3 * a + 3] = d[r], -d[r]
        return J[:, free], 0.5 * (np.sum(d * d, axis=1) - lengths ** 2)

    cable_density = np.where(bar, 0.0, q)
    J, g = constraints()
    lam = np.linalg.lstsq(J.T, -(density_matrix(cable_density) @ X.ravel())[free], rcond=None)[0]
    for _ in range(50):
        density = cable_density.copy()
        density[bars] = lam
        W = density_matrix(density)
        residual = np.concatenate([(W @ X.ravel())[free], g])
        if np.linalg.norm(residual) <= 1e-14 * np.linalg.norm(X):
            break
        kkt = np.block([[W[np.ix_(free, free)], J.T], [J, np.zeros((len(bars), len(bars)))]])
        step = np.linalg.solve(kkt, -residual)
        x = X.ravel().copy()
        x[free] += step[:len(free)]
        X = x.reshape(X.shape)
        lam = lam + step[len(free):]
        J, g = constraints()
    return X


def saddle_net(cells, spacing, c):
    """(cells+1)² nodes on z = c (x² − y²), plan centred on 0; cables along x and y lines,
    those between two boundary nodes left out."""
    n = cells + 1
    coord = [(i - cells / 2) * spacing for i in range(n)]
    X = np.array([[coord[i], coord[j], c * (coord[i] ** 2 - coord[j] ** 2)] for j in range(n) for i in range(n)])
    boundary = [j * n + i for j in range(n) for i in range(n) if i in (0, cells) or j in (0, cells)]
    members = []
    for j in range(n):
        for i in range(cells):
            for a, b in ((j * n + i, j * n + i + 1), (i * n + j, (i + 1) * n + j)):
                if not (a in boundary and b in boundary):
                    members.append((a, b, False))
    return X, members, boundary


def arrays(members):
    """Member ends (m × 2) and the bar mask of a member list of (a, b, bar?)."""
    return np.array([(a, b) for a, b, _ in members]), np.array([is_bar for _, _, is_bar in members])


def held_nodes(X, nodes):
    held = np.zeros(X.shape, dtype=bool)
    held[nodes] = True
    return held


def report(name, X, members, held, t):
    """Check the prestress (signs, balance, prestress stability); print the case's counts."""
    ends, bar = arrays(members)
    check_state(X, ends, held, bar, t)
    _, m, s, _, _ = counts(equilibrium_matrix(X, ends, held))
    smallest = prestress_stability(X, ends, held, t)
    assert smallest is None or smallest > 0, f"{name}: not prestress-stable (smallest eigenvalue {smallest})"
    shown = "none (m = 0)" if smallest is None else f"{smallest:.6g} N/m"
    print(f"{name}: {len(X)} nodes, {len(members)} members, m = {m}, s = {s}, "
          f"smallest eigenvalue of Mᵀ K_G M = {shown}")


def report_no_equilibrium(name, X, members, diagonals, held, force):
    """Check that the diagonals remove the mechanism (m = 0 with them, 1 without), that the load
    works on it (F·d > 0) and that every diagonal shortens along d; print those facts."""
    A_all = equilibrium_matrix(X, arrays(members + diagonals)[0], held)
    rank_all, m_all, _, _, _ = counts(A_all)
    rank, m, _, U, _ = counts(equilibrium_matrix(X, arrays(members)[0], held))
    assert m_all == 0 and m == 1, f"{name}: m = {m_all} with the diagonals, {m} without"
    d = U[:, rank]
    work = force[~held] @ d
    d, work = (d, work) if work > 0 else (-d, -work)
    assert work > 0, f"{name}: the load does no work on the mechanism"
    shortening = A_all[:, len(members):].T @ d
    assert np.all(shortening < 0), f"{name}: a diagonal lengthens along the mechanism"
    print(f"{name}: {len(X)} nodes, {len(members) + len(diagonals)} members, rank {rank_all} = free dofs "
          f"with the diagonals, {rank} (m = 1) without; F·d = {work:.6g} N on the unit mechanism d, along "
          f"which the diagonals' lengths change by {', '.join(f'{x:.6g}' for x in shortening)}")


def number(x):
    return repr(float(x))


def write_case(out, name, comment, X, members, t, body, member_ids=None):
    """OUT/name.toml (comment, `[structure]`, then `body`) and its two tables."""
    ids = list(range(len(members))) if member_ids is None else member_ids
    os.makedirs(os.path.join(out, name), exist_ok=True)
    with open(os.path.join(out, name, "nodes.csv"), "w") as f:
        f.write("node,x,y,z\n")
        for i, p in enumerate(X):
            f.write(f"{i},{number(p[0])},{number(p[1])},{number(p[2])}\n")
    with open(os.path.join(out, name, "members.csv"), "w") as f:
        f.write("member,a,b,kind,young,section,prestress\n")
        for j, (a, b, is_bar), t0 in zip(ids, members, t):
            young, section = BAR if is_bar else CABLE
            f.write(f"{j},{a},{b},{'bar' if is_bar else 'cable'},{number(young)},{number(section)},{number(t0)}\n")
    lines = [f"# {line}".rstrip() for line in comment.strip().splitlines()]
    with open(os.path.join(out, f"{name}.toml"), "w") as f:
        f.write("\n".join(lines) + f'\n[structure]\nnodes = "{name}/nodes.csv"\nmembers = "{name}/members.csv"\n\n'
                + body.strip() + "\n")


LARGE = """
[load]
alpha = [0.25, 0.5, 1.0]

[solver]
methods = ["newton"]
"""

SIMPLEX = """
The 3-strut simplex, written by scripts/tensegrity_cases.py: triangles of circumradius 1 m,
1.5 m apart, the top one turned 150°; bar i from bottom node i to top node 3+i, side cables
from bottom i to top 3+(i−1 mod 3), top ring 3-4-5. Bottom triangle pinned, its ring cables
left out (between held nodes). Prestress: the single self-stress state (SVD of the equilibrium
matrix), 2 kN in the top ring, 3.17 kN in the side cables, −4.89 kN in the bars.
m = 1, s = 1: an infinitesimal mechanism (the top twisting and sinking) that only the prestress
stiffens (Mᵀ K_G M = 3118 N/m), so the linear model refuses it. Each top node carries 300 N
sideways and 1 kN down: the top moves 22.4 / 37.1 / 55.6 mm at α = 0.25 / 0.5 / 1, against
25.5 / 50.9 / 101.9 mm linearised (K + K_G(t0)): the geometry stiffens the mechanism as it opens.
(Large-displacement answers: OpenSees corotTruss, scripts/peers/corot.py, and an independent
Newton on the energy, agreeing to 1e-10.)
"""

PRISM4 = """
A 4-strut prism, written by scripts/tensegrity_cases.py: squares of circumradius 1 m, 1.5 m
apart, the top one turned 135°; bar i from bottom node i to top node 4+i, side cables from
bottom i to top 4+(i−1 mod 4), top ring 4-5-6-7. Bottom square pinned, its ring cables left out
(between held nodes). Prestress: the single self-stress state (SVD), 2 kN in the top ring,
3.37 kN in the side cables, −4.76 kN in the bars. m = 1, s = 1, prestress-stable
(Mᵀ K_G M = 2314 N/m). Each top node carries 100 N sideways and 300 N down: the top moves
13.4 / 24.8 / 41.7 mm at α = 0.25 / 0.5 / 1, against 13.9 / 27.7 / 55.5 mm linearised
(K + K_G(t0)). (OpenSees corotTruss, scripts/peers/corot.py, and an independent Newton agree
to 1e-10.)
"""

TOWER = """
A 3-stage simplex tower (Snelson style), written by scripts/tensegrity_cases.py. Stage k = 0, 1, 2
has bottom nodes 6k..6k+2 and top nodes 6k+3..6k+5, bars from bottom i to top i and side cables
from bottom i to top i−1 (as the simplex); between stages, each bottom node of the upper stage
hangs from two top nodes of the lower one (saddle cables) and is tied down to a bottom node of
the lower stage, and each top node of the lower stage is tied up to a top node of the upper
stage; a top ring closes stage 2. Geometry by form-finding from stacked simplices (r = 1 m,
h = 1.5 m, 1 m apart): a stationary point of ½ Σ q ℓ² over the cables (q = 1) with the bars'
2.446 m kept; 2.90 m high. Base triangle (nodes 0-2) pinned. Prestress: the single self-stress
state (SVD), 1 kN in the top ring, 0.65 to 1.96 kN in the cables, −3.44 to −3.99 kN in the bars.
m = 1, s = 1, prestress-stable (Mᵀ K_G M = 2708 N/m). A lateral load of (500, 866, 0) N on each
top node (15-17) moves the top 1.33 / 2.69 / 25.3 mm at α = 0.25 / 0.5 / 1: between 0.5 and 1
the side cables 3 and 11 (stages 0 and 1) go slack and the tower leans on its mechanism
(linearised, K + K_G(t0) with unilateral cables: 1.32 / 2.63 / 26.8 mm, the same two slack).
(OpenSees corotTruss, scripts/peers/corot.py, and an independent Newton agree to 1e-10.)
"""

SADDLE = """
A 6 × 6-cell cable net (7 × 7 nodes, 1 m apart in plan, centred on the origin) on the saddle
z = 0.1 (x² − y²), written by scripts/tensegrity_cases.py. Node j·7 + i is at x = i − 3,
y = j − 3. Cables along the x and y lines; the 24 boundary nodes are held, the cables between
two of them left out. Prestress: uniform force density q = 5 kN/m on every cable (t = q ℓ,
5.0 to 5.6 kN), in equilibrium at the interior nodes because z's second differences along x and
y are +2c and −2c; it is the net's single self-stress state (s = 1). m = 16, all stiffened by the
tension (smallest eigenvalue of Mᵀ K_G M: 8984 N/m). 300 N down on every interior node moves it
0.276 / 0.552 / 1.107 mm at α = 0.25 / 0.5 / 1, against 0.276 / 0.551 / 1.103 mm linearised
(K + K_G(t0)): a taut net is nearly linear. (OpenSees corotTruss, scripts/peers/corot.py, and an
independent Newton agree to 1e-10.)
"""

NO_EQUILIBRIUM = """
No equilibrium in the linear model, written by scripts/tensegrity_cases.py: the simplex of
simplex.toml (same nodes, members 0-8 and prestress) plus three unprestressed diagonal cables
90, 91, 92 from top node 3+i to the bottom node it is not joined to ((i+2) mod 3). With them
the equilibrium matrix has full rank (9 = free dofs, m = 0, s = 3), so the linear model takes
the case; without them the simplex's mechanism d (the top twisting and sinking) is back (m = 1).
The load, 1 kN tangential (counter-clockwise seen from above) on each top node, works on d
(F·d = 1643 N for a unit d) and the three diagonals shorten along it: their bilateral linear
answer would be −1374 N each (every other cable stays taut). Unilateral, the diagonals go
slack, nothing resists d, and the energy is unbounded below: no equilibrium exists under
geometry = "linear". (With geometry = "large" the prestress stiffens d and the simplex carries
the load: 91.6 mm, the three diagonals slack, by OpenSees corotTruss.)
"""


def simplex(out):
    X, members = prism(3, 1.0, 1.5)
    held = held_nodes(X, [0, 1, 2])
    t = self_stress(X, arrays(members)[0], held, 3, 2000.0)
    report("simplex", X, members, held, t)
    write_case(out, "simplex", SIMPLEX, X, members, t, """
[[supports.fix]]
nodes = [0, 1, 2]

[[load.point]]
nodes = [3, 4, 5]
force = [300.0, 0.0, -1000.0]
""" + LARGE)


def prism4(out):
    X, members = prism(4, 1.0, 1.5)
    held = held_nodes(X, [0, 1, 2, 3])
    t = self_stress(X, arrays(members)[0], held, 4, 2000.0)
    report("prism4", X, members, held, t)
    write_case(out, "prism4", PRISM4, X, members, t, """
[[supports.fix]]
nodes = [0, 1, 2, 3]

[[load.point]]
nodes = [4, 5, 6, 7]
force = [100.0, 0.0, -300.0]
""" + LARGE)


def tower(out):
    start = tower_start(3, 1.0, 1.5, 1.0)
    members = tower_topology(3)
    held = held_nodes(start, [0, 1, 2])
    ends, bar = arrays(members)
    X = form_find(start, ends, held, bar, 1.0)
    t = self_stress(X, ends, held, 18, 1000.0)
    report("tower", X, members, held, t)
    write_case(out, "tower", TOWER, X, members, t, """
[[supports.fix]]
nodes = [0, 1, 2]

[[load.point]]
nodes = [15, 16, 17]
force = [500.0, 866.0, 0.0]
""" + LARGE)


TOWER2 = """
A 2-stage tower to design (issue 46), written by scripts/tensegrity_cases.py: the 3-stage
tower's topology on two stages (form-found the same way), plus a cable ring on stage 0's top
(3-4-5, group ring0) and a bar triangle on stage 1's bottom (6-7-8, group struts1); base
(nodes 0-2) pinned. s = 6, m = 0; by the 11 groups of the `group` column (by symmetry),
s₂ = 2 grouped self-stress states: the two bar groups' forces fix the design
(`tensolve design cases/tower2-design.toml`). Its prestress column is 0: the design fills it.
Each top node (9-11) carries 200 N sideways and 500 N down.
"""


def tower2_groups(j):
    """The group of member j of the 2-stage tower with its two extra rings."""
    if j < 12:
        return ["bars0", "sides0", "bars1", "sides1"][j // 3]
    if j < 15:
        return "ring1"
    if j < 27:
        return ["saddle-a", "saddle-b", "lower-tie", "upper-tie"][(j - 15) % 4]
    return "ring0" if j < 30 else "struts1"


def tower2(out):
    start = tower_start(2, 1.0, 1.5, 1.0)
    members = tower_topology(2)
    ends, bar = arrays(members)
    X = form_find(start, ends, held_nodes(start, [0, 1, 2]), bar, 1.0)
    members += [(3, 4, False), (4, 5, False), (5, 3, False), (6, 7, True), (7, 8, True), (8, 6, True)]
    write_case(out, "tower2-design", TOWER2, X, members, [0.0] * len(members), """
[[supports.fix]]
nodes = [0, 1, 2]

[[load.point]]
nodes = [9, 10, 11]
force = [200.0, 0.0, -500.0]

[prestress]
from = "design"
targets = { bars0 = -3000.0, bars1 = -2000.0 }
""" + LARGE)
    # The group column, last.
    path = os.path.join(out, "tower2-design", "members.csv")
    with open(path) as f:
        lines = f.read().splitlines()
    with open(path, "w") as f:
        f.write(lines[0] + ",group\n")
        for j, line in enumerate(lines[1:]):
            f.write(f"{line},{tower2_groups(j)}\n")


def saddle(out):
    X, members, boundary = saddle_net(6, 1.0, 0.1)
    held = held_nodes(X, boundary)
    ends, _ = arrays(members)
    t = 5000.0 * np.linalg.norm(X[ends[:, 1]] - X[ends[:, 0]], axis=1)
    report("saddle-net", X, members, held, t)
    write_case(out, "saddle-net", SADDLE, X, members, t, f"""
[[supports.fix]]
nodes = {boundary}

[load]
nodal = [0.0, 0.0, -300.0]
alpha = [0.25, 0.5, 1.0]

[solver]
methods = ["newton"]
""")


def simplex_no_equilibrium(out):
    X, members = prism(3, 1.0, 1.5)
    held = held_nodes(X, [0, 1, 2])
    t = self_stress(X, arrays(members)[0], held, 3, 2000.0)
    diagonals = [((i + 2) % 3, 3 + i, False) for i in range(3)]
    force = np.zeros(X.shape)
    for i in range(3):
        a = math.atan2(X[3 + i, 1], X[3 + i, 0])
        force[3 + i] = [round(-1000.0 * math.sin(a), 6) + 0.0, round(1000.0 * math.cos(a), 6) + 0.0, 0.0]
    report_no_equilibrium("simplex-no-equilibrium", X, members, diagonals, held, force)
    points = "\n".join(f"[[load.point]]\nnodes = [{3 + i}]\nforce = [{', '.join(number(f) for f in force[3 + i])}]\n"
                       for i in range(3))
    write_case(out, "simplex-no-equilibrium", NO_EQUILIBRIUM, X, members + diagonals, list(t) + [0.0] * 3, f"""
[[supports.fix]]
nodes = [0, 1, 2]

{points}
[load]
alpha = [1.0]

[model]
geometry = "linear"

[solver]
methods = ["newton"]
""", member_ids=list(range(len(members))) + [90, 91, 92])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "cases"),
                        help="directory of the cases (default: the repository's cases/)")
    out = os.path.normpath(parser.parse_args().out)
    for write in (simplex, prism4, tower, tower2, saddle, simplex_no_equilibrium):
        write(out)


if __name__ == "__main__":
    main()
