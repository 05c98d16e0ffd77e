#!/usr/bin/env bash
# micro-macro shared by MPI ranks (issue 25): solve time per iteration and values exchanged per
# iteration on 1, 2 and 4 ranks, one rayon thread per rank, for the 64 x 64 grid (16 x 16
# substructures of 4 x 4 modules, alpha 0.15) and the 128 x 128 grid (8 x 8 substructures of
# 16 x 16 modules, alpha 0.0375); beside them one process with 2 rayon threads. Medians of N
# runs (default 3), the rank counts interleaved. On a 2-core machine 4 ranks are
# oversubscribed: two ranks share a core. Ranks are not bound to cores (`--bind-to none`): with
# one rank OpenMPI would otherwise bind it, and its two threads, to one core.
# Usage: scripts/mpi-bench.sh [N]   (needs mpirun and python3; builds with --features mpi into
# target/mpi so that the default binary is left alone; TENSOLVE_BIN=path runs that binary
# instead, unbuilt: an older build, for a before/after comparison)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
bin=${TENSOLVE_BIN:-}
if [ -z "$bin" ]; then
  export CARGO_TARGET_DIR=target/mpi
  cargo build --release --quiet --features mpi
  bin=target/mpi/release/tensolve
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cases=(
  "64 cases/scale-64-latin.toml solver.subdomains=[16,16] load.alpha=[0.15]"
  "128 cases/scale-128.toml solver.subdomains=[8,8] load.alpha=[0.0375]"
)
mpi=(mpirun --oversubscribe --allow-run-as-root --bind-to none)
for k in $(seq 1 "$runs"); do
  for spec in "${cases[@]}"; do
    read -r n case subdomains alpha <<< "$spec"
    for setup in "1 1" "2 1" "4 1" "1 2"; do
      read -r ranks threads <<< "$setup"
      dir="$out/$n-$ranks-$threads-$k"
      RAYON_NUM_THREADS=$threads "${mpi[@]}" -x RAYON_NUM_THREADS -n "$ranks" "$bin" run "$case" \
        --out "$dir" --solver micro-macro --set "$subdomains" --set "$alpha" \
        --set 'solver.reference="none"' --set output.plots=false --set output.history=false \
        2> "$dir.log" > /dev/null
    done
  done
done
python3 - "$out" "$runs" <<'PY'
import csv, re, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
print("| grid | ranks x threads | iterations | solve s | ms / iteration | values in per iteration (rank 0) |")
print("|---|---|---|---|---|---|")
for n in ["64", "128"]:
    for ranks, threads in [("1", "1"), ("2", "1"), ("4", "1"), ("1", "2")]:
        per_it, solve, its, values = [], [], None, None
        for k in range(1, runs + 1):
            base = f"{out}/{n}-{ranks}-{threads}-{k}"
            with open(f"{base}/summary.csv") as f:
                row = next(csv.DictReader(f))
            its = int(row["iterations"])
            solve.append(float(row["solve_seconds"]))
            per_it.append(1e3 * float(row["solve_seconds"]) / max(its, 1))
            m = re.search(r"received (\d+) values", open(f"{base}.log").read())
            values = int(m.group(1)) if m else 0
        vpi = f"{values / max(its, 1):,.0f} ({8 * values / max(its, 1) / 1e6:.2f} MB)" if values else "-"
        print(f"| {n} x {n} | {ranks} x {threads} | {its} | {statistics.median(solve):.2f} | "
              f"{statistics.median(per_it):.1f} | {vpi} |")
PY
