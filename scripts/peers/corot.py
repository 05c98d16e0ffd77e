#!/usr/bin/env python3
"""OpenSees corotational peer of tensolve's large-displacement model (SPEC §8).

    python3 scripts/peers/corot.py CASE.toml OUT_DIR [--increments 20] [--modes N] [--arc-step 0.005]

Reads a `[structure]` case (its two tables, `[[supports.fix]]` by `nodes` or `box` with
`dofs`, `[[load.point]]`, `load.nodal`, `load.alpha`, `cables.unilateral`) and solves it as a
3-D OpenSees truss of `corotTruss` elements: member j of section S carries
`InitStressMaterial` (σ0 = t0 / S) over `Elastic E 0 Eneg`, Eneg = 0 for unilateral cables and
E otherwise. With engineering strain on the initial length L this is tensolve's law on the exact
length, τ = t0 + (E S / L)(ℓ − L), clipped at 0 for unilateral cables. The prestress being a
self-stress, α = 0 is the prestressed state (no displacement). A member whose rest length
changes by Δℓ0 (`[[load.rest_length_change]]`, `[[load.temperature]]`: α_T ΔT L) carries
instead `InitStrainMaterial` (ε0 = t0 / (E S) − Δℓ0 / L) over the same elastic material: the
actuated structure moves before any load, and the first load step starts from the unmoved one.

The load path is the case's α in increasing order, each reached from the previous one (from 0
for the first) in `--increments` equal load steps (LoadControl), each step solved by Newton to
an unbalance of 1e-12 · (‖α_max F‖ + ‖Σ|t0| n‖) over the free dofs (UmfPack). For each α it
writes `OUT_DIR/displacements/alpha{α}.csv` (node,ux,uy,uz) and `OUT_DIR/forces/alpha{α}.csv`
(member,kind,force; axial force, tension > 0), α labelled as tensolve labels its files.

With `--modes N` it also writes, for each α, `OUT_DIR/modes/alpha{α}.csv` (mode,frequency_Hz):
the N lowest natural frequencies of OpenSees `eigen` (`-fullGenLapack`, dense) at that state,
the corotTruss tangent there (material `E S / L` along the member plus the geometric `τ / ℓ`
across it, slack cables none) against each member's mass ρ S L from the members table's
`density` column (`-rho ρS`), plus `[[modal.point_mass]]` (`mass` kg on each component of the
nodes its `nodes` or `box` selects, OpenSees `mass`), consistent (`-cMass 1`: `ρ S L / 6 [2I I; I 2I]`, tensolve's
default) or lumped (`-cMass 0`: `ρ S L / 2` on each end) as the case's `modal.mass` says.

A case with `load.path = "arc-length"` is followed by OpenSees' `ArcLength` instead
(`solve_arc`: steps of `--arc-step` m in ‖ΔU‖), each α the first point of the path where the
load reaches it, and `OUT_DIR/limits.csv` lists the limit loads passed.

Refused (exit 2, with the reason): a `[grid]` case, a non-zero `supports.fix` displacement,
`load.self_weight`, `prestress.from`. Exit 1 when a load step does not converge.
Needs `pip install openseespy numpy` (on Debian also `apt-get install libblas3 liblapack3
libgfortran5`).
"""

import argparse
import csv
import math
import os
import sys
import tomllib
from decimal import Decimal

import numpy as np

NODE_HEADER = ["node", "x", "y", "z"]
MEMBER_HEADER = ["member", "a", "b", "kind", "young", "section", "prestress"]
AXES = {"x": 0, "y": 1, "z": 2}
RELATIVE_UNBALANCE = 1e-12
MAX_NEWTON_ITERATIONS = 50


class CaseError(Exception):
    """A case this peer cannot read or does not support (exit 2)."""


def alpha_label(alpha):
    """α as tensolve writes it in file names: Rust's `{}` for f64 (1 → `1`, 0.05 → `0.05`),
    or its `{:e}` (`1e-250`) when that is longer than 24 characters."""
    text = repr(float(alpha))
    full = format(Decimal(text), "f")
    if full.endswith(".0"):
        full = full[:-2]
    if len(full) <= 24:
        return full
    mantissa, _, exponent = text.partition("e")
    return f"{mantissa}e{int(exponent)}"


def read_table(path, header):
    """Rows of a tensolve CSV table (lines starting with `#` ignored), checked against its header."""
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    rows = list(csv.reader(lines))
    if not rows or rows[0][: len(header)] != header:
        raise CaseError(f"{path}: the header must start with {','.join(header)}")
    return [dict(zip(rows[0], row)) for row in rows[1:] if row]


def selected_nodes(entry, key, ids, X):
    """Node indices chosen by a `nodes = [...]` or `box = {min, max}` entry."""
    if ("nodes" in entry) == ("box" in entry):
        raise CaseError(f"{key}: give exactly one of `nodes` and `box`")
    if "nodes" in entry:
        index = {node: i for i, node in enumerate(ids)}
        unknown = [n for n in entry["nodes"] if n not in index]
        if unknown:
            raise CaseError(f"{key}.nodes: {unknown} are not ids of the nodes table")
        return [index[n] for n in entry["nodes"]]
    lo, hi = np.array(entry["box"]["min"], float), np.array(entry["box"]["max"], float)
    tol = 1e-9 * max(np.abs(X).max(), 1.0)
    inside = np.all((X >= lo - tol) & (X <= hi + tol), axis=1)
    if not inside.any():
        raise CaseError(f"{key}.box holds no node")
    return list(np.flatnonzero(inside))


def load_case(path):
    """The structure, supports, load and α of a tensolve `[structure]` case."""
    with open(path, "rb") as f:
        case = tomllib.load(f)
    if "structure" not in case:
        raise CaseError("only `[structure]` cases are supported (write a grid as tables with scripts/grid_csv.py)")
    if "self_weight" in case.get("load", {}):
        raise CaseError("`load.self_weight` is not supported by this peer")
    if "from" in case.get("prestress", {}):
        raise CaseError("`prestress.from` is not supported by this peer: give the prestress in the members table")
    if "alpha" not in case.get("load", {}):
        raise CaseError("`load.alpha` is required")
    base = os.path.dirname(os.path.abspath(path))
    nodes = read_table(os.path.join(base, case["structure"]["nodes"]), NODE_HEADER)
    members = read_table(os.path.join(base, case["structure"]["members"]), MEMBER_HEADER)
    ids = [int(r["node"]) for r in nodes]
    X = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in nodes])
    index = {node: i for i, node in enumerate(ids)}
    unilateral = case.get("cables", {}).get("unilateral", True)
    bars = []
    for r in members:
        if r["kind"] not in ("bar", "cable"):
            raise CaseError(f"member {r['member']}: kind must be bar or cable, not {r['kind']!r}")
        bars.append(r["kind"] == "bar")
    held = np.zeros(X.shape, dtype=bool)
    for i, fix in enumerate(case.get("supports", {}).get("fix", [])):
        key = f"supports.fix[{i}]"
        if any(d != 0.0 for d in fix.get("displacement", [0.0, 0.0, 0.0])):
            raise CaseError(f"{key}.displacement: prescribed (non-zero) displacements are not supported by this peer")
        dofs = [AXES[d] for d in fix.get("dofs", ["x", "y", "z"])]
        for n in selected_nodes(fix, key, ids, X):
            held[n, dofs] = True
    F = np.zeros(X.shape)
    F[~held.all(axis=1)] += np.array(case["load"].get("nodal", [0.0, 0.0, 0.0]), float)
    for i, point in enumerate(case["load"].get("point", [])):
        for n in selected_nodes(point, f"load.point[{i}]", ids, X):
            F[n] += np.array(point["force"], float)
    F[held] = 0.0
    point_mass = np.zeros(len(ids))
    for i, entry in enumerate(case.get("modal", {}).get("point_mass", [])):
        for n in selected_nodes(entry, f"modal.point_mass[{i}]", ids, X):
            point_mass[n] += float(entry["mass"])
    rest_change = rest_length_changes(case, members, X, [index[int(r["a"])] for r in members],
                                      [index[int(r["b"])] for r in members])
    alpha = case["load"]["alpha"]
    if isinstance(alpha, dict):
        lo, hi, steps = float(alpha["from"]), float(alpha["to"]), int(alpha["steps"])
        # tensolve's values to the last bit (its file names carry them): rounded to 12 digits.
        alpha = [lo] if steps == 1 else [float(f"{lo + (hi - lo) * i / (steps - 1):.11e}") for i in range(steps)]
    return {
        "ids": ids,
        "X": X,
        "member_ids": [int(r["member"]) for r in members],
        "ends": np.array([[index[int(r["a"])], index[int(r["b"])]] for r in members]),
        "bar": np.array(bars),
        "young": np.array([float(r["young"]) for r in members]),
        "section": np.array([float(r["section"]) for r in members]),
        "t0": np.array([float(r["prestress"]) for r in members]),
        "rest_change": rest_change,
        "density": np.array([float(r.get("density") or 0.0) for r in members]),
        "consistent_mass": case.get("modal", {}).get("mass", "consistent") == "consistent",
        "point_mass": point_mass,
        "unilateral": unilateral,
        "held": held,
        "F": F,
        "alphas": sorted({float(a) for a in alpha}),
        "geometry": case.get("model", {}).get("geometry"),
        "path": case["load"].get("path", "load-control"),
    }


def rest_length_changes(case, members, X, a, b):
    """Δℓ0 per member (m): `[[load.rest_length_change]]` (`change`) and `[[load.temperature]]`
    (α_T ΔT L), each on `members = [ids]`, a members-table `group`, a `kind`, or
    (temperature) every member."""
    ids = [int(r["member"]) for r in members]
    groups = [r.get("group") for r in members]
    length = np.linalg.norm(X[b] - X[a], axis=1)
    change = np.zeros(len(members))

    def chosen(entry, everyone):
        if "members" in entry:
            wanted = {int(m) for m in entry["members"]}
            return [j for j, m in enumerate(ids) if m in wanted]
        if "group" in entry:
            return [j for j, g in enumerate(groups) if g == entry["group"]]
        if "kind" in entry:
            return [j for j, r in enumerate(members) if r["kind"] == entry["kind"]]
        if everyone:
            return list(range(len(ids)))
        raise CaseError("a rest-length change names no members")

    for entry in case["load"].get("rest_length_change", []):
        for j in chosen(entry, False):
            change[j] += float(entry["change"])
    for entry in case["load"].get("temperature", []):
        for j in chosen(entry, True):
            change[j] += float(entry["expansion"]) * float(entry["change"]) * length[j]
    return change


def unbalance_scale(c):
    """‖α_max F‖ + ‖Σ |t0| |n|‖ over the free dofs: what the Newton test is relative to."""
    d = c["X"][c["ends"][:, 1]] - c["X"][c["ends"][:, 0]]
    share = np.abs(d / np.linalg.norm(d, axis=1)[:, None]) * np.abs(c["t0"])[:, None]
    internal = np.zeros(c["X"].shape)
    np.add.at(internal, c["ends"][:, 0], share)
    np.add.at(internal, c["ends"][:, 1], share)
    free = ~c["held"]
    load = max(abs(a) for a in c["alphas"]) * np.linalg.norm(c["F"][free])
    return load + np.linalg.norm(internal[free])


def build_model(c, ops):
    """The OpenSees model: nodes, supports, corotTruss members and the reference load (α = 1)."""
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 3)
    for i, (x, y, z) in enumerate(c["X"]):
        ops.node(i + 1, float(x), float(y), float(z))
        if c["held"][i].any():
            ops.fix(i + 1, *(int(h) for h in c["held"][i]))
    for j, (a, b) in enumerate(c["ends"]):
        e, s, t0 = c["young"][j], c["section"][j], c["t0"][j]
        negative = e if c["bar"][j] or not c["unilateral"] else 0.0
        ops.uniaxialMaterial("Elastic", 2 * j + 1, e, 0.0, negative)
        material = 2 * j + 1
        change = c["rest_change"][j]
        if change != 0.0:
            # An initial strain: the material sees ε + ε0, ε0 = t0 / (E S) − Δℓ0 / L, so that
            # τ = t0 − (E S / L) Δℓ0 + (E S / L)(ℓ − L), clipped at 0 for unilateral cables.
            length = float(np.linalg.norm(c["X"][b] - c["X"][a]))
            strain = t0 / (e * s) - change / length
            ops.uniaxialMaterial("InitStrainMaterial", 2 * j + 2, 2 * j + 1, strain)
            material = 2 * j + 2
        elif t0 != 0.0:
            ops.uniaxialMaterial("InitStressMaterial", 2 * j + 2, 2 * j + 1, t0 / s)
            material = 2 * j + 2
        # Mass per unit length ρS, spread on the ends as tensolve's modal.mass says.
        mass = ["-rho", float(c["density"][j] * s), "-cMass", int(c["consistent_mass"])]
        ops.element("corotTruss", j + 1, int(a) + 1, int(b) + 1, float(s), material, *mass)
    for i, m in enumerate(c["point_mass"]):
        if m > 0.0:
            ops.mass(i + 1, float(m), float(m), float(m))
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for i, f in enumerate(c["F"]):
        if np.any(f != 0.0):
            ops.load(i + 1, *(float(v) for v in f))
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormUnbalance", RELATIVE_UNBALANCE * unbalance_scale(c), MAX_NEWTON_ITERATIONS)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 0.0)
    ops.analysis("Static")


def write_state(c, ops, out_dir, alpha):
    """displacements/alpha{α}.csv and forces/alpha{α}.csv of the current state."""
    label = alpha_label(alpha)
    for sub in ("displacements", "forces"):
        os.makedirs(os.path.join(out_dir, sub), exist_ok=True)
    with open(os.path.join(out_dir, "displacements", f"alpha{label}.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["node", "ux", "uy", "uz"])
        for i, node in enumerate(c["ids"]):
            w.writerow([node, *(repr(float(u)) for u in ops.nodeDisp(i + 1))])
    with open(os.path.join(out_dir, "forces", f"alpha{label}.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["member", "kind", "force"])
        for j, member in enumerate(c["member_ids"]):
            force = ops.basicForce(j + 1)[0]
            w.writerow([member, "bar" if c["bar"][j] else "cable", repr(float(force))])


def write_modes(ops, out_dir, alpha, count):
    """modes/alpha{α}.csv: the `count` lowest frequencies of the current state's tangent."""
    eigenvalues = ops.eigen("-fullGenLapack", count)
    os.makedirs(os.path.join(out_dir, "modes"), exist_ok=True)
    with open(os.path.join(out_dir, "modes", f"alpha{alpha_label(alpha)}.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["mode", "frequency_Hz"])
        for i, eigenvalue in enumerate(eigenvalues):
            # f = ω / 2π with ω² the eigenvalue (0 for a zero or negative one, as tensolve).
            w.writerow([i + 1, repr(math.sqrt(max(eigenvalue, 0.0)) / (2.0 * math.pi))])


def solve(c, out_dir, increments, modes=0):
    """Follow the load path; write each α's state (and its `modes` lowest frequencies).
    Returns False when a step fails."""
    import openseespy.opensees as ops

    build_model(c, ops)
    current = 0.0
    for alpha in c["alphas"]:
        if alpha != current:
            ops.integrator("LoadControl", (alpha - current) / increments)
            if ops.analyze(increments) != 0:
                print(f"corot: no convergence on the way from alpha = {current} to {alpha}", file=sys.stderr)
                return False
            current = alpha
        write_state(c, ops, out_dir, alpha)
        if modes > 0:
            write_modes(ops, out_dir, alpha, modes)
    ops.wipe()
    return True


def limit_of(loads):
    """The load at a local maximum of λ near three equal steps `loads`: the vertex of the
    parabola through them."""
    a, b, c = loads
    curvature = a - 2.0 * b + c
    return b if curvature >= 0.0 else b - (c - a) ** 2 / (8.0 * curvature)


def displacements(c, ops):
    """Every node's displacement, (nodes, 3)."""
    return np.array([ops.nodeDisp(i + 1) for i in range(len(c["ids"]))])


def solve_arc(c, out_dir, arc_step, max_steps=100000):
    """Follow the equilibrium path by OpenSees' `ArcLength` integrator (constant step
    `arc_step` in ‖ΔU‖, the load's weight 0: cylindrical), through limit points. Each α is the
    first point of the path where λ = α: the step that passes it is followed by one
    `LoadControl` step back onto α, and the path goes on from there.

    `ArcLength` takes the sign of each step's Δλ from the last step's; where the load falls
    along the path it turns back (measured: at the simplex's limit point, after a landing). A
    step whose ΔU points against the last one's is that turn: the path is walked on by
    `DisplacementControl` on the component that moved most in the last forward step (by as
    much, the same way) while the load falls, and by `ArcLength` again once it rises for two
    steps.

    Writes each α's state and `limits.csv`: the load of each local maximum of λ passed, by the
    parabola through the three equal steps (of one integrator) around it. Returns False when a
    step fails or the path ends before the last α."""
    import openseespy.opensees as ops

    build_model(c, ops)
    targets = [a for a in c["alphas"]]
    if targets and targets[0] == 0.0:
        write_state(c, ops, out_dir, 0.0)
        targets.pop(0)
    arc = ("ArcLength", arc_step, 0.0)
    integrator, issue = arc, True
    loads, limits, steady, turns, rising = [0.0], [], 0, 0, 0
    last_step = None
    for _ in range(max_steps):
        if not targets:
            break
        if issue:
            ops.integrator(*integrator)
            issue, steady = False, 0
        before = displacements(c, ops)
        if ops.analyze(1) != 0:
            print(f"corot: no convergence of a step at lambda = {loads[-1]}", file=sys.stderr)
            return False
        load = ops.getLoadFactor(1)
        loads.append(load)
        step = displacements(c, ops) - before
        if integrator is arc and last_step is not None and np.vdot(step, last_step) < 0.0:
            # ArcLength turned back: walk on by displacement control. Turned back at a
            # maximum, the limit is the vertex of the parabola through the last three
            # forward steps (rising to the last).
            turns += 1
            if steady >= 3 and loads[-2] > loads[-3]:
                limits.append(limit_of(loads[-4:-1]))
            node, dof = np.unravel_index(np.abs(last_step).argmax(), last_step.shape)
            integrator = ("DisplacementControl", int(node) + 1, int(dof) + 1, float(last_step[node, dof]))
            issue, last_step, rising = True, None, 0
            continue
        last_step = step
        steady += 1
        rising = rising + 1 if load > loads[-2] else 0
        if integrator is not arc and rising >= 2:
            integrator, issue = arc, True
        # Three equal steps with the middle load the largest: a limit point.
        if steady >= 3 and loads[-2] > loads[-3] and loads[-2] >= loads[-1]:
            limits.append(limit_of(loads[-3:]))
        if loads[-2] < targets[0] <= load:
            alpha = targets.pop(0)
            ops.integrator("LoadControl", alpha - load)
            if ops.analyze(1) != 0:
                print(f"corot: no convergence landing on alpha = {alpha}", file=sys.stderr)
                return False
            write_state(c, ops, out_dir, alpha)
            loads.append(alpha)
            issue, last_step = True, None
    ops.wipe()
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "limits.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["limit_alpha"])
        for limit in limits:
            w.writerow([repr(float(limit))])
    print(f"corot: arc path: {len(loads) - 1} steps, {turns} turn(s) walked past, limits {limits}",
          file=sys.stderr)
    if targets:
        print(f"corot: the arc path did not reach alpha = {targets[0]} in {max_steps} steps", file=sys.stderr)
        return False
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("out_dir")
    parser.add_argument("--increments", type=int, default=20, help="load steps between two α (default 20)")
    parser.add_argument("--modes", type=int, default=0, help="the lowest natural frequencies to write per α")
    parser.add_argument("--arc-step", type=float, default=0.005,
                        help="the arc step in ‖ΔU‖, m, when the case asks for load.path = \"arc-length\" (default 0.005)")
    args = parser.parse_args()
    if args.increments < 1:
        parser.error("--increments must be at least 1")
    if args.modes < 0:
        parser.error("--modes must be at least 0")
    try:
        case = load_case(args.case)
    except (CaseError, KeyError, ValueError, OSError, tomllib.TOMLDecodeError) as e:
        print(f"corot: {args.case}: {e}", file=sys.stderr)
        return 2
    if case["geometry"] not in (None, "large"):
        print(f"corot: note: the case asks for geometry = {case['geometry']!r}; this peer solves large displacements",
              file=sys.stderr)
    if args.modes > 0 and not ((case["density"] > 0.0).any() or (case["point_mass"] > 0.0).any()):
        print(f"corot: {args.case}: --modes needs a mass: a `density` column in the members table, or "
              "[[modal.point_mass]]",
              file=sys.stderr)
        return 2
    if case["path"] == "arc-length":
        if args.modes > 0:
            print(f"corot: {args.case}: --modes is not supported along an arc-length path", file=sys.stderr)
            return 2
        return 0 if solve_arc(case, args.out_dir, args.arc_step) else 1
    return 0 if solve(case, args.out_dir, args.increments, args.modes) else 1


if __name__ == "__main__":
    sys.exit(main())
