#!/usr/bin/env bash
# A load-sweep script: the slack fraction against the lower-cable prestress p and the load
# factor α, one `tensolve run` per prestress with `--set`, collected into one CSV.
#
# Usage: scripts/sweep.sh CASE OUT_CSV P1 [P2 ...]
#   CASE     a case file (its solver.methods and load.alpha are used; newton is cheapest)
#   OUT_CSV  the CSV written: prestress,solver,alpha,slack_fraction,converged
#   P1 ...   lower-cable prestress values, N
# Example: scripts/sweep.sh cases/paper-exact.toml out/prestress.csv 1000 2000 4000
# The binary is $TENSOLVE if set, else target/release/tensolve (built by cargo if missing).
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,11p' "$0" >&2
  exit 2
fi
case_file=$1
out_csv=$2
shift 2
bin=${TENSOLVE:-}
if [ -z "$bin" ]; then
  root=$(cd "$(dirname "$0")/.." && pwd)
  bin=$root/target/release/tensolve
  [ -x "$bin" ] || cargo build --release --quiet --manifest-path "$root/Cargo.toml"
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tmp_csv=$work/sweep.csv
echo "prestress,solver,alpha,slack_fraction,converged" > "$tmp_csv"
for p in "$@"; do
  # Exit 1 (a solve did not converge) still leaves a complete summary; the row says so.
  status=0
  "$bin" run "$case_file" --set "prestress.lower_cable=$p" --out "$work/p$p" --quiet || status=$?
  if [ "$status" -ne 0 ] && [ "$status" -ne 1 ]; then
    echo "sweep.sh: tensolve failed at prestress $p (exit $status)" >&2
    exit "$status"
  fi
  awk -F, -v p="$p" '
    NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    { print p "," $col["solver"] "," $col["alpha"] "," $col["slack_fraction"] "," $col["converged"] }
  ' "$work/p$p/summary.csv" >> "$tmp_csv"
done
mkdir -p "$(dirname "$out_csv")"
mv "$tmp_csv" "$out_csv"
echo "wrote $out_csv"
