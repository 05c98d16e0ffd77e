#!/usr/bin/env bash
# Regenerate every figure the README shows, into docs/figures/<case>/:
#
#   paper/          the paper's case with all four solvers (tensions, slack fraction, deformed
#                   grid, LATIN error and indicator per iteration: the paper's Figures 6-11)
#   paper-sweep/    slack fraction against alpha from 0 to 1.2 (Figure 7)
#   paper-braced/   the paper's case on braced modules
#   paper-linear/, paper-linear-braced/
#                   the linear case, standard and braced modules (together: Figure 12)
#   paper-bench/    bench.svg: e against wall time for the four solvers at alpha = 1
#
# The runs go to out/figures/<case>/. Each case is run from a copy with `output.plots = true`
# (the case files themselves leave plots off). Needs a tensolve that knows `output.plots`;
# the script stops at the first run or copy that fails.
#
# Usage: scripts/figures.sh        (from any directory)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

cargo build --release --quiet
tensolve="${CARGO_TARGET_DIR:-$root/target}/release/tensolve"
figures="$root/docs/figures"
runs="$root/out/figures"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

# The case file $1 with `plots = true` in its [output] section (added when it has none).
with_plots() {
    local case="$1" copy
    copy="$scratch/$(basename "$case")"
    if grep -q '^plots *= *true' "$case"; then
        cp "$case" "$copy"
    elif grep -q '^\[output\]' "$case"; then
        sed 's/^\[output\].*/&\nplots = true/' "$case" >"$copy"
    else
        printf '%s\n\n[output]\nplots = true\n' "$(cat "$case")" >"$copy"
    fi
    echo "$copy"
}

# Copy the SVG files of directory $1 into docs/figures/$2/, replacing what was there.
publish() {
    local from="$1" name="$2"
    if ! compgen -G "$from/*.svg" >/dev/null; then
        echo "figures.sh: no SVG in $from" >&2
        exit 1
    fi
    rm -rf "${figures:?}/$name"
    mkdir -p "$figures/$name"
    cp "$from"/*.svg "$figures/$name/"
    echo "figures.sh: $(ls "$from"/*.svg | wc -l) figure(s) in docs/figures/$name/"
}

# Run case $1 with plots (extra arguments go to `tensolve run`) and publish its plots.
run_case() {
    local case="$1" name
    shift
    name="$(basename "$case" .toml)"
    "$tensolve" run "$(with_plots "$case")" --out "$runs/$name" --quiet "$@"
    publish "$runs/$name/plots" "$name"
}

run_case cases/paper.toml --solver newton,pcg-lcp,mono-latin,micro-macro
run_case cases/paper-sweep.toml
run_case cases/paper-braced.toml
run_case cases/paper-linear.toml
run_case cases/paper-linear-braced.toml

"$tensolve" bench cases/paper-bench.toml --out "$runs/paper-bench" --quiet
publish "$runs/paper-bench" paper-bench
