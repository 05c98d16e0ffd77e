#!/usr/bin/env bash
# Wall time to e <= 1e-3, set-up included, of micro-macro and mono-latin on the 16 x 16 and
# 64 x 64 grids of the LATIN weak-scaling series: the median of N runs of `tensolve bench`
# (default 5), runs of the two cases interleaved, and the ratio micro-macro / mono-latin.
# Usage: scripts/latin-ratio.sh [N]   (needs python3; builds the release binary first)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-5}
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for k in $(seq 1 "$runs"); do
  for case in scale-16-latin scale-64-latin; do
    ./target/release/tensolve bench "cases/$case.toml" --out "$out/$case-$k" > /dev/null 2>> "$out/log"
  done
done
python3 - "$out" "$runs" <<'PY'
import csv, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
for case in ["scale-16-latin", "scale-64-latin"]:
    times = {}
    for k in range(1, runs + 1):
        first = {}
        with open(f"{out}/{case}-{k}/bench.csv") as f:
            for row in csv.DictReader(f):
                if float(row["error_e"]) <= 1e-3 and row["solver"] not in first:
                    first[row["solver"]] = float(row["seconds"])
        for solver, t in first.items():
            times.setdefault(solver, []).append(t)
    med = {s: statistics.median(v) for s, v in times.items()}
    cells = ", ".join(f"{s} {med[s]:.3f} s" for s in sorted(med))
    ratio = med["micro-macro"] / med["mono-latin"]
    print(f"{case}: median time to e <= 1e-3 over {runs} runs: {cells}; ratio {ratio:.2f}")
PY
