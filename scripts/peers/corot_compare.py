#!/usr/bin/env python3
"""tensolve's large-displacement newton against the OpenSees corotational peer, α by α.

    python3 scripts/peers/corot_compare.py CASE.toml TENSOLVE_RUN_DIR [--rtol 1e-6] [--increments 20] [--modes]
        [--arc-step 0.005] [--limit-rtol 1e-6]
    python3 scripts/peers/corot_compare.py CASE.toml --print-only

Runs scripts/peers/corot.py on the case into a temporary directory, then reads tensolve's
TENSOLVE_RUN_DIR/displacements/newton_alpha{α}.csv (node,x,y,z,ux,uy,uz) and
TENSOLVE_RUN_DIR/tensions/newton_alpha{α}.csv (member,kind,node_a,node_b,tension; cables, slack
ones exactly 0). Per α it passes when
  max |Δu| / max |u| ≤ rtol (every displacement component, u the peer's),
  max |Δτ| / max |τ| ≤ rtol over the cables (τ the peer's),
  and the slack cables are the same (tensolve: τ == 0; peer: |τ| ≤ 1e-9 max |τ|),
and with `--modes` (tensolve run with `output.modes = N`, the members given a `density`)
  max |Δf| / f ≤ rtol over the N lowest natural frequencies, against the peer's OpenSees
  `eigen` at the same state (tensolve's TENSOLVE_RUN_DIR/modes/newton_alpha{α}.csv; the
  peer's N is the row count of tensolve's file at the first α),
and, where the case follows an arc-length path (`load.path = "arc-length"`, the peer on
OpenSees' `ArcLength`),
  |Δ| / limit ≤ --limit-rtol between the largest limit load the peer passed (its
  `limits.csv`) and the largest `limit_alpha` of tensolve's summary.csv,
and prints one line per α with the figures. Exit 0 when every α passes, 1 otherwise (or when
the peer does not converge), 2 on usage errors (or a case the peer refuses).

`--print-only` prints the peer's largest displacement and slack cables per α, without tensolve.
"""

import argparse
import csv
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corot import CaseError, alpha_label, load_case  # noqa: E402

SLACK_RELATIVE = 1e-9


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def peer_state(out, alpha):
    """The peer's displacements {node: u} and member forces {member: (kind, τ)} at α."""
    label = alpha_label(alpha)
    u = {int(r["node"]): np.array([float(r["ux"]), float(r["uy"]), float(r["uz"])])
         for r in read_csv(os.path.join(out, "displacements", f"alpha{label}.csv"))}
    forces = {int(r["member"]): (r["kind"], float(r["force"]))
              for r in read_csv(os.path.join(out, "forces", f"alpha{label}.csv"))}
    return u, forces


def tensolve_state(run_dir, alpha):
    """tensolve's displacements {node: u} and cable tensions {member: τ} at α."""
    label = alpha_label(alpha)
    u = {int(r["node"]): np.array([float(r["ux"]), float(r["uy"]), float(r["uz"])])
         for r in read_csv(os.path.join(run_dir, "displacements", f"newton_alpha{label}.csv"))}
    tension = {int(r["member"]): float(r["tension"])
               for r in read_csv(os.path.join(run_dir, "tensions", f"newton_alpha{label}.csv"))}
    return u, tension


def frequencies(path):
    """The frequency_Hz column of a modes file, in mode order."""
    return np.array([float(r["frequency_Hz"]) for r in read_csv(path)])


def compare_modes(alpha, peer_out, run_dir, rtol):
    """One α's frequency figures and whether they pass."""
    label = alpha_label(alpha)
    theirs = frequencies(os.path.join(peer_out, "modes", f"alpha{label}.csv"))
    ours = frequencies(os.path.join(run_dir, "modes", f"newton_alpha{label}.csv"))
    if len(ours) != len(theirs):
        return f", FAIL: {len(ours)} modes, the peer {len(theirs)}", False
    # Relative to each frequency (to the largest where one is 0: a mechanism no stress holds).
    scale = np.maximum(theirs, 1e-12 * theirs.max())
    worst = float((np.abs(ours - theirs) / scale).max())
    return f", {len(ours)} modes {theirs[0]:.6g}..{theirs[-1]:.6g} Hz, max |df|/f {worst:.2e}", worst <= rtol


def relative(difference, scale):
    if scale > 0.0:
        return difference / scale
    return 0.0 if difference == 0.0 else float("inf")


def compare(alpha, peer, ours, rtol):
    """One α's line and whether it passes."""
    u, forces = peer
    ours_u, ours_tension = ours
    nodes = sorted(u)
    if sorted(ours_u) != nodes:
        return f"alpha {alpha_label(alpha)}: FAIL, the node ids differ", False
    U = np.array([u[n] for n in nodes])
    V = np.array([ours_u[n] for n in nodes])
    du = relative(np.abs(U - V).max(), np.abs(U).max())
    cables = sorted(m for m, (kind, _) in forces.items() if kind == "cable")
    if sorted(ours_tension) != cables:
        return f"alpha {alpha_label(alpha)}: FAIL, the cables of the tensions table differ", False
    tau = np.array([forces[m][1] for m in cables])
    ours_tau = np.array([ours_tension[m] for m in cables])
    scale = np.abs(tau).max() if len(cables) else 0.0
    dtau = relative(np.abs(tau - ours_tau).max(), scale) if len(cables) else 0.0
    peer_slack = {m for m, t in zip(cables, tau) if abs(t) <= SLACK_RELATIVE * scale}
    our_slack = {m for m, t in zip(cables, ours_tau) if t == 0.0}
    ok = du <= rtol and dtau <= rtol and peer_slack == our_slack
    line = (f"alpha {alpha_label(alpha)}: max |u| {1e3 * np.linalg.norm(U, axis=1).max():.6g} mm "
            f"(tensolve {1e3 * np.linalg.norm(V, axis=1).max():.6g} mm), max |du|/max |u| {du:.2e}, "
            f"max |dtau|/max |tau| {dtau:.2e}, slack {len(peer_slack)} (tensolve {len(our_slack)})")
    if peer_slack != our_slack:
        line += f", slack only in the peer {sorted(peer_slack - our_slack)}, only in tensolve {sorted(our_slack - peer_slack)}"
    return line + (": pass" if ok else ": FAIL"), ok


def print_only(alpha, peer):
    u, forces = peer
    tau = {m: t for m, (kind, t) in forces.items() if kind == "cable"}
    scale = max((abs(t) for t in tau.values()), default=0.0)
    slack = sorted(m for m, t in tau.items() if abs(t) <= SLACK_RELATIVE * scale)
    deflection = max(np.linalg.norm(v) for v in u.values())
    print(f"alpha {alpha_label(alpha)}: max |u| {1e3 * deflection:.6g} mm, {len(slack)} slack cable(s) {slack}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case")
    parser.add_argument("run_dir", nargs="?", help="tensolve's output directory of the case")
    parser.add_argument("--rtol", type=float, default=1e-6)
    parser.add_argument("--increments", type=int, default=20, help="the peer's load steps between two α")
    parser.add_argument("--arc-step", type=float, default=0.005,
                        help="the peer's arc step in ‖ΔU‖, m, along an arc-length path (default 0.005)")
    parser.add_argument("--limit-rtol", type=float, default=1e-6,
                        help="the limit loads' relative difference allowed along an arc-length path (default 1e-6)")
    parser.add_argument("--print-only", action="store_true", help="print the peer's answers, compare nothing")
    parser.add_argument("--modes", action="store_true",
                        help="compare the natural frequencies of TENSOLVE_RUN_DIR/modes too")
    args = parser.parse_args()
    if args.modes and args.run_dir is None:
        parser.error("--modes compares with TENSOLVE_RUN_DIR's modes: give it")
    if not args.print_only and args.run_dir is None:
        parser.error("give TENSOLVE_RUN_DIR, or --print-only")
    if args.run_dir is not None and not os.path.isdir(args.run_dir):
        parser.error(f"{args.run_dir} is not a directory")
    try:
        alphas = load_case(args.case)["alphas"]
    except (CaseError, KeyError, ValueError, OSError) as e:
        print(f"corot_compare: {args.case}: {e}", file=sys.stderr)
        return 2
    peer_script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corot.py")
    peer_args = ["--increments", str(args.increments), "--arc-step", str(args.arc_step)]
    if args.modes:
        try:
            count = len(frequencies(os.path.join(args.run_dir, "modes", f"newton_alpha{alpha_label(alphas[0])}.csv")))
        except (OSError, KeyError, ValueError) as e:
            print(f"corot_compare: --modes: cannot read tensolve's modes: {e!r}", file=sys.stderr)
            return 2
        peer_args += ["--modes", str(count)]
    with tempfile.TemporaryDirectory() as out:
        run = subprocess.run([sys.executable, peer_script, args.case, out, *peer_args])
        if run.returncode != 0:
            return run.returncode
        passed = True
        for alpha in alphas:
            peer = peer_state(out, alpha)
            if args.print_only:
                print_only(alpha, peer)
                continue
            try:
                ours = tensolve_state(args.run_dir, alpha)
            except (OSError, KeyError, ValueError) as e:
                print(f"alpha {alpha_label(alpha)}: FAIL, cannot read tensolve's tables: {e!r}")
                passed = False
                continue
            line, ok = compare(alpha, peer, ours, args.rtol)
            if args.modes:
                try:
                    modes_line, modes_ok = compare_modes(alpha, out, args.run_dir, args.rtol)
                except (OSError, KeyError, ValueError) as e:
                    modes_line, modes_ok = f", FAIL, cannot read the modes: {e!r}", False
                line = line.removesuffix(": pass").removesuffix(": FAIL") + modes_line
                ok = ok and modes_ok
                line += ": pass" if ok else ": FAIL"
            print(line)
            passed = passed and ok
        if os.path.exists(os.path.join(out, "limits.csv")) and not args.print_only:
            line, ok = compare_limits(out, args.run_dir, args.limit_rtol)
            print(line)
            passed = passed and ok
    return 0 if passed else 1


def compare_limits(peer_out, run_dir, rtol):
    """The largest limit load passed, the peer's against tensolve's `limit_alpha`."""
    theirs = [float(r["limit_alpha"]) for r in read_csv(os.path.join(peer_out, "limits.csv"))]
    ours = [float(r["limit_alpha"]) for r in read_csv(os.path.join(run_dir, "summary.csv"))
            if r.get("limit_alpha")]
    if not theirs or not ours:
        return f"limit: FAIL, limit loads: the peer {theirs}, tensolve {sorted(set(ours))}", theirs == ours
    peer, own = max(theirs), max(ours)
    difference = abs(peer - own) / abs(peer)
    ok = difference <= rtol
    return (f"limit: the peer {peer!r}, tensolve {own!r}, |difference| / limit {difference:.2e}"
            + (": pass" if ok else ": FAIL")), ok


if __name__ == "__main__":
    sys.exit(main())
