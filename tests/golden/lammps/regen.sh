#!/usr/bin/env bash
# Regenerate all LAMMPS golden data in this directory (see README.md).
# Needs: lmp (LAMMPS with the GRANULAR package; tested with the Debian 12 package
# 20220106.git7586adbb6a = "29 Sep 2021 - Update 2") and python3 (standard library only).
set -euo pipefail
export PYTHONDONTWRITEBYTECODE=1
cd "$(dirname "${BASH_SOURCE[0]}")"

LMP=${LMP:-lmp}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

run_lmp() {  # run_lmp CASE INPUT [lmp -var args...]
    local case=$1 input=$2
    shift 2
    if ! "$LMP" -in "$input" -log none -screen "$WORK/$case.screen" "$@"; then
        echo "LAMMPS failed for $case:" >&2
        tail -n 20 "$WORK/$case.screen" >&2
        exit 1
    fi
    echo "ran $case"
}

for e in 0.2 0.45 0.9; do
    damp=$(python3 post.py tsuji-arg "$e")
    run_lmp "pp_headon_e$e" pp_headon.lammps -var e "$e" -var damp "$damp" -var mu 0.3 \
        -var out "pp_headon_e$e.csv" -var final "$WORK/pp_headon_e$e.final"
    run_lmp "pw_headon_e$e" pw_headon.lammps -var e "$e" -var damp "$damp" -var mu 0.3 \
        -var out "pw_headon_e$e.csv" -var final "$WORK/pw_headon_e$e.final"
done

damp=$(python3 post.py tsuji-arg 0.45)
run_lmp pw_oblique_mu0.3_e0.45 pw_oblique.lammps -var e 0.45 -var damp "$damp" -var mu 0.3 \
    -var out pw_oblique_mu0.3_e0.45.csv -var final "$WORK/pw_oblique_mu0.3_e0.45.final"
run_lmp pp_oblique_mu0.3_e0.45 pp_oblique.lammps -var e 0.45 -var damp "$damp" -var mu 0.3 \
    -var out pp_oblique_mu0.3_e0.45.csv -var final "$WORK/pp_oblique_mu0.3_e0.45.final"

# JKR pull-off: undamped (e = 1) and Tsuji-damped with the e = 0.9 prefactor
run_lmp pp_jkr_pulloff pp_jkr_pulloff.lammps -var dmodel velocity -var damp 0.0 \
    -var out pp_jkr_pulloff.csv -var raw "$WORK/pp_jkr_pulloff.raw" \
    -var final "$WORK/pp_jkr_pulloff.final"
damp=$(python3 post.py tsuji-arg 0.9)
run_lmp pp_jkr_pulloff_e0.9 pp_jkr_pulloff.lammps -var dmodel tsuji -var damp "$damp" \
    -var out pp_jkr_pulloff_e0.9.csv -var raw "$WORK/pp_jkr_pulloff_e0.9.raw" \
    -var final "$WORK/pp_jkr_pulloff_e0.9.final"

python3 post.py summary "$WORK" > "$WORK/summary.csv"
mv "$WORK/summary.csv" summary.csv
echo "wrote summary.csv"

# independent Python re-integration of the head-on and oblique cases (fails on mismatch)
python3 check_reference.py "$WORK"
