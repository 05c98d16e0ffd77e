#!/usr/bin/env python3
"""tensolve's newton against two peers on one case, side by side in one run.

    python3 scripts/peers/peers.py cases/paper.toml 1.0
    python3 scripts/peers/peers.py cases/scale-64.toml 0.15 --repeat 3
    python3 scripts/peers/peers.py cases/paper.toml 1.0 --warm

Peers (not part of CI; `pip install openseespy osqp numpy scipy`, and on Debian
`apt-get install libblas3 liblapack3 libgfortran5` for OpenSees):

* OpenSees: the same grid as truss elements (small displacements), cables tension-only
  (`Elastic` with `Eneg = 0`) and every link prestressed by an initial strain
  (`InitStrainMaterial`, ε0 = t0 / EA), one load step of Newton (ten if one fails) to an
  unbalance of 1e-10 · (‖F‖ + ‖|B|ᵀ|t0|‖), tensolve's r(U) ≤ 1e-10 with τ ≈ t0.
* OSQP at 1e-6: the energy as a QP in (U, y): min ½ Σ_bars k (B U)² + Σ_bars t0 B U
  + ½ Σ_cables k y² − Fᵀ U, with y ≥ B U + t0/k and y ≥ 0 (a cable's tension is k y).

The geometry is tensolve's own (read from the VTU file it writes), so all three solve the
same structure; the case must keep the paper's materials and prestress (only `grid.modules`
and `supports.clamp` are read). Times are medians over `--repeat` runs of set-up + solve:
tensolve's from its summary.csv (`setup_seconds + solve_seconds`, in-process), the peers'
from building their model (nodes, elements / matrices) to the answer, in-process too.

Each tensolve run is a fresh process, whose first touch of every page is part of its time;
the peers run again and again in one warm Python process. `--warm` times tensolve warm too:
the criterion median of `newton/setup+solve` (taut stiffness, set-up and solve, repeated in
one process; the structure itself, about 0.4 ms on the paper case, is built once outside)
from `cargo bench --bench solvers`, run here for the one benchmark group that is this case
at this α (the paper case at 1.0, `scale-64.toml` at 0.15).
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
import xml.etree.ElementTree as ET

import numpy as np

# The paper's materials and prestress (README "Case files" defaults).
E_CABLE, A_CABLE = 1e11, 0.5e-4
E_BAR, A_BAR = 2e11, 2.8e-4
P, L, H = 2000.0, 1.0, 0.5
PRESTRESS = {0: P, 1: math.sqrt(2.0) * P, 2: math.sqrt(1.0 + 4.0 * H * H / (L * L)) * P, 3: 0.0,
             4: -math.sqrt(5.0 + 4.0 * H * H / (L * L)) * P}
NODAL = np.array([0.0, 0.0, -40.0])


def tensolve_runs(exe, case_path, alpha, repeat, out):
    """Run tensolve newton `repeat` times; return (median seconds, summary row, vtu path)."""
    case = tomllib.load(open(case_path, "rb"))
    nx, ny = case["grid"]["modules"]
    clamp = case.get("supports", {}).get("clamp", "lower-x-edges")
    text = f"""[grid]
modules = [{nx}, {ny}]
[supports]
clamp = "{clamp}"
[load]
alpha = [{alpha!r}]
[solver]
methods = ["newton"]
[output]
tensions = false
displacements = false
vtk = true
"""
    path = os.path.join(out, "case.toml")
    open(path, "w").write(text)
    times, row = [], None
    for _ in range(repeat):
        subprocess.run([exe, "run", path, "--out", out, "--quiet"], check=True)
        lines = open(os.path.join(out, "summary.csv")).read().splitlines()
        header, values = lines[0].split(","), lines[1].split(",")
        row = dict(zip(header, values))
        times.append(float(row["setup_seconds"]) + float(row["solve_seconds"]))
    vtu = os.path.join(out, "vtk", f"newton_alpha{row['alpha']}.vtu")
    return statistics.median(times), row, (nx, ny, clamp), vtu


# Benchmark groups of benches/solvers.rs: (case file name, alpha) -> group.
CRITERION_GROUPS = {("paper.toml", 1.0): "paper_alpha1", ("scale-64.toml", 0.15): "scale64_alpha0.15"}


def tensolve_warm(case_path, alpha):
    """Criterion median (s) of newton set-up + solve on this case, measured now."""
    group = CRITERION_GROUPS.get((os.path.basename(case_path), alpha))
    if group is None:
        sys.exit(f"--warm: no benchmark group for {case_path} at alpha = {alpha}; "
                 f"benches/solvers.rs has {sorted(CRITERION_GROUPS)}")
    name = f"{group}/newton/setup+solve"
    subprocess.run(["cargo", "bench", "--bench", "solvers", "--", f"^{name.replace('+', '[+]')}$"],
                   check=True, stdout=subprocess.DEVNULL)
    path = os.path.join("target", "criterion", group, "newton_setup+solve", "new", "estimates.json")
    return json.load(open(path))["median"]["point_estimate"] * 1e-9


def read_vtu(path):
    """Points (n × 3), links (m × 2) and link kinds from tensolve's VTU."""
    root = ET.parse(path).getroot()
    arrays = {a.get("Name"): a.text for a in root.iter("DataArray")}
    points = np.array(arrays["Points"].split(), dtype=float).reshape(-1, 3) if "Points" in arrays else None
    if points is None:
        pts = root.find(".//Points/DataArray")
        points = np.array(pts.text.split(), dtype=float).reshape(-1, 3)
    links = np.array(arrays["connectivity"].split(), dtype=int).reshape(-1, 2)
    kind = np.array(arrays["kind"].split(), dtype=int)
    return points, links, kind


def clamped_nodes(points, nx, ny, clamp):
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    lower = np.isclose(z, 0.0)
    on_x = np.isclose(x, 0.0) | np.isclose(x, nx * L)
    on_y = np.isclose(y, 0.0) | np.isclose(y, ny * L)
    if clamp == "lower-x-edges":
        return lower & on_x
    if clamp == "lower-y-edges":
        return lower & on_y
    if clamp == "lower-all-edges":
        return lower & (on_x | on_y)
    if clamp == "lower-corners":
        return lower & on_x & on_y
    return np.zeros(len(points), dtype=bool)


def link_data(points, links, kind):
    d = points[links[:, 1]] - points[links[:, 0]]
    length = np.linalg.norm(d, axis=1)
    bar = kind == 4
    ea = np.where(bar, E_BAR * A_BAR, E_CABLE * A_CABLE)
    t0 = np.array([PRESTRESS[k] for k in kind])
    return d / length[:, None], length, ea, t0, bar


def opensees(points, links, kind, clamped, alpha):
    """Set-up + solve with OpenSees; returns (seconds, slack count, max deflection, steps)."""
    import openseespy.opensees as ops

    direction, length, ea, t0, bar = link_data(points, links, kind)
    nodal = np.zeros((len(points), 3))
    np.add.at(nodal, links[:, 0], np.abs(direction) * np.abs(t0)[:, None])
    np.add.at(nodal, links[:, 1], np.abs(direction) * np.abs(t0)[:, None])
    internal_scale = float(np.linalg.norm(nodal[~clamped]))
    for steps in (1, 10):
        start = time.perf_counter()
        ops.wipe()
        ops.model("basic", "-ndm", 3, "-ndf", 3)
        for i, (x, y, z) in enumerate(points):
            ops.node(i + 1, x, y, z)
            if clamped[i]:
                ops.fix(i + 1, 1, 1, 1)
        # One material per link kind: elastic (tension-only for cables) with its prestrain.
        for k in sorted(set(kind.tolist())):
            is_bar = k == 4
            e, a = (E_BAR, A_BAR) if is_bar else (E_CABLE, A_CABLE)
            ops.uniaxialMaterial("Elastic", 100 + k, e, 0.0, e if is_bar else 0.0)
            ops.uniaxialMaterial("InitStrainMaterial", 200 + k, 100 + k, PRESTRESS[k] / (e * a))
        for j, (a, b) in enumerate(links):
            area = A_BAR if bar[j] else A_CABLE
            ops.element("Truss", j + 1, int(a) + 1, int(b) + 1, area, 200 + int(kind[j]))
        ops.timeSeries("Linear", 1)
        ops.pattern("Plain", 1, 1)
        free = np.flatnonzero(~clamped)
        for i in free:
            ops.load(int(i) + 1, *(alpha * NODAL))
        # tensolve's scale of r(U): ‖F‖ + ‖|B|ᵀ|τ|‖, with τ ≈ t0 (the prestress dominates).
        scale = abs(alpha) * np.linalg.norm(NODAL) * math.sqrt(len(free)) + internal_scale
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("UmfPack")
        ops.test("NormUnbalance", 1e-10 * scale, 50)
        ops.algorithm("Newton")
        ops.integrator("LoadControl", 1.0 / steps)
        ops.analysis("Static")
        ok = ops.analyze(steps)
        seconds = time.perf_counter() - start
        if ok == 0:
            forces = np.array([ops.basicForce(j + 1)[0] for j in range(len(links))])
            slack = int(np.sum((~bar) & (forces <= 1e-9 * P)))
            disp = np.array([ops.nodeDisp(int(i) + 1) for i in range(len(points))])
            return seconds, slack, float(np.max(np.linalg.norm(disp, axis=1))), steps
    return float("nan"), -1, float("nan"), -1


def osqp_solve(points, links, kind, clamped, alpha):
    """Set-up + solve with OSQP at 1e-6; returns (seconds, slack count, max deflection, iters)."""
    import osqp
    import scipy.sparse as sp

    start = time.perf_counter()
    direction, length, ea, t0, bar = link_data(points, links, kind)
    k = ea / length
    free_node = np.cumsum(~clamped) - 1
    n = 3 * int(np.sum(~clamped))
    rows, cols, vals = [], [], []
    for sign, end in ((-1.0, links[:, 0]), (1.0, links[:, 1])):
        keep = ~clamped[end]
        for c in range(3):
            rows.append(np.flatnonzero(keep))
            cols.append(3 * free_node[end[keep]] + c)
            vals.append(sign * direction[keep, c])
    B = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(len(links), n))
    Bb, Bc = B[bar], B[~bar]
    kb, kc, t0b, t0c = k[bar], k[~bar], t0[bar], t0[~bar]
    m = Bc.shape[0]
    f = np.tile(alpha * NODAL, n // 3)
    P_ = sp.block_diag([Bb.T @ sp.diags(kb) @ Bb, sp.diags(kc)], format="csc")
    q = np.concatenate([Bb.T @ t0b - f, np.zeros(m)])
    A = sp.vstack([sp.hstack([-Bc, sp.identity(m)]), sp.hstack([sp.csr_matrix((m, n)), sp.identity(m)])], format="csc")
    lower = np.concatenate([t0c / kc, np.zeros(m)])
    upper = np.full(2 * m, np.inf)
    solver = osqp.OSQP()
    solver.setup(P=sp.triu(P_, format="csc"), q=q, A=A, l=lower, u=upper, eps_abs=1e-6, eps_rel=1e-6,
                 max_iter=1_000_000, verbose=False)
    result = solver.solve()
    seconds = time.perf_counter() - start
    u, y = result.x[:n], result.x[n:]
    tension = kc * y
    slack = int(np.sum(tension <= 1e-6 * P))
    deflection = float(np.max(np.linalg.norm(u.reshape(-1, 3), axis=1)))
    return seconds, slack, deflection, result.info.iter, result.info.status


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("alpha", type=float)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--tensolve", default="target/release/tensolve")
    parser.add_argument("--warm", action="store_true",
                        help="time tensolve by its criterion benchmark (warm, in one process)")
    args = parser.parse_args()
    if "grid" not in tomllib.load(open(args.case, "rb")):
        print(f"peers.py: {args.case} has no [grid]: this comparison rebuilds the paper's module "
              "grid in its peers (only `grid.modules` and `supports.clamp` are read); for a "
              "[structure] case use scripts/peers/corot.py (OpenSees corotTruss, large "
              "displacements) or scripts/peers/corot_compare.py", file=sys.stderr)
        sys.exit(2)
    with tempfile.TemporaryDirectory() as out:
        ours, row, (nx, ny, clamp), vtu = tensolve_runs(args.tensolve, args.case, args.alpha, args.repeat, out)
        points, links, kind = read_vtu(vtu)
    how = "fresh process"
    if args.warm:
        ours, how = tensolve_warm(args.case, args.alpha), "criterion median, warm"
    clamped = clamped_nodes(points, nx, ny, clamp)
    direction, length, ea, t0, bar = link_data(points, links, kind)
    print(f"{args.case} at alpha = {args.alpha}: {len(points)} nodes ({int(clamped.sum())} clamped), {len(links)} links")
    ref_slack, ref_defl = int(row["slack_cables"]), float(row["max_deflection"])
    print(f"{'solver':<10} {'median s':>10} {'x tensolve':>10} {'slack':>7} {'max defl. m':>14}  notes")
    print(f"{'tensolve':<10} {ours:>10.4f} {1.0:>10.1f} {ref_slack:>7} {ref_defl:>14.9f}  newton, r <= 1e-10, {row['iterations']} iterations, {how}")
    runs = [opensees(points, links, kind, clamped, args.alpha) for _ in range(args.repeat)]
    t = statistics.median(r[0] for r in runs)
    s, d, steps = runs[-1][1], runs[-1][2], runs[-1][3]
    print(f"{'opensees':<10} {t:>10.4f} {t / ours:>10.1f} {s:>7} {d:>14.9f}  {steps} load step(s)")
    runs = [osqp_solve(points, links, kind, clamped, args.alpha) for _ in range(args.repeat)]
    t = statistics.median(r[0] for r in runs)
    s, d, iters, status = runs[-1][1:]
    print(f"{'osqp':<10} {t:>10.4f} {t / ours:>10.1f} {s:>7} {d:>14.9f}  eps 1e-6, {iters} iterations, {status}")


if __name__ == "__main__":
    sys.exit(main())
