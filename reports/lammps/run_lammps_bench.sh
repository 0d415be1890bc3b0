#!/usr/bin/env bash
# Speed of LAMMPS pair_style peri/pmb on Miranda's Model A lattice (83 x 9 x 7 = 5229 nodes,
# lambda = 0.05 m, delta = 2*sqrt(3)*lambda), for comparison with libpd.
#
# Usage (from the repository root):
#   bash reports/lammps/run_lammps_bench.sh [STEPS]        # STEPS default 600
# Environment:
#   LMP=/path/to/lmp        LAMMPS binary (default: lmp on PATH)
#   REPS=3                  repetitions per configuration (median is reported)
#   BENCH_MPI_RANKS=2       optional: also time an MPI run with that many ranks (needs mpirun)
#   BENCH_DIAGNOSTIC=0      skip the diagnostic 1-thread run without the contact loop (default 1)
#   PD=build/bin/pd         optional: after each LAMMPS 1-thread run, time libpd on the same
#                           lattice (pd bench model-a-benchmark.yaml --threads 1) and report the
#                           median of the same-repetition ratios libpd/LAMMPS ("libpd" in the JSON)
#
# Prints one JSON object on stdout; progress goes to stderr.
# Configurations: serial, 1 thread (OMP_NUM_THREADS=1, plain peri/pmb); and, only if this LAMMPS
# build has the OPENMP package with peri/pmb/omp, 2 threads via "-sf omp -pk omp 2".
#
# Bond counting: fix PERI_NEIGH prints "total # of bonds = N" where N is the sum over atoms of
# npartner[i], i.e. every bond is stored (and computed) from both ends. N = partner entries;
# unordered bonds = N / 2. Throughput: bond_updates_per_second = bonds_unordered * steps / seconds
# (one update = one bond's force computed once per step), the same definition libpd uses.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
input="$here/model-a.in"
LMP="${LMP:-lmp}"
REPS="${REPS:-3}"
STEPS="${1:-600}"
MPI_RANKS="${BENCH_MPI_RANKS:-}"
DIAGNOSTIC="${BENCH_DIAGNOSTIC:-1}"
PD="${PD:-}"

die() { echo "run_lammps_bench.sh: error: $*" >&2; exit 1; }
log() { echo "[lammps-bench] $*" >&2; }

if ! command -v "$LMP" >/dev/null 2>&1; then
  echo "run_lammps_bench.sh: error: LAMMPS binary '$LMP' not found on PATH." >&2
  echo "  Install the Debian package (apt-get install lammps, provides /usr/bin/lmp)" >&2
  echo "  or set LMP=/path/to/lmp." >&2
  exit 127
fi
[[ "$STEPS" =~ ^[1-9][0-9]*$ ]] || die "STEPS must be a positive integer, got '$STEPS'"
[[ "$REPS" =~ ^[1-9][0-9]*$ ]] || die "REPS must be a positive integer, got '$REPS'"
[[ -f "$input" ]] || die "input file not found: $input"
LMP="$(command -v "$LMP")"

help="$("$LMP" -h 2>&1 || true)"
lammps_version="$(printf '%s\n' "$help" |
  sed -n 's/^Large-scale Atomic\/Molecular Massively Parallel Simulator - //p' | head -n1)"
[[ -n "$lammps_version" ]] || die "'$LMP -h' did not print a LAMMPS version banner"
deb_version="$(dpkg-query -W -f='${Version}' lammps 2>/dev/null || true)"
printf '%s\n' "$help" | grep -qw 'peri/pmb' || die "this LAMMPS build has no pair_style peri/pmb (PERI package)"

# OPENMP accelerator: package installed AND the peri/pmb/omp style compiled in
omp_available=false
if printf '%s\n' "$help" | grep -Eqw 'OPENMP|USER-OMP' &&
   printf '%s\n' "$help" | grep -qw 'peri/pmb/omp'; then
  omp_available=true
fi

work="$(mktemp -d "${TMPDIR:-/tmp}/lammps-bench.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"   # LAMMPS may write small side files (e.g. log.cite) into the cwd

base_args=(-in "$input" -log none -echo none -nocite)

# run_lmp OUTFILE [extra lmp args...]  (environment via the caller)
run_lmp() {
  local out="$1"; shift
  if ! "$@" >"$out" 2>&1; then
    tail -n 20 "$out" >&2
    die "LAMMPS run failed: $*"
  fi
  grep -q '^Loop time of' "$out" || { tail -n 20 "$out" >&2; die "no 'Loop time' line in LAMMPS output"; }
}

# parse OUTFILE -> "loop_s pair_avg_s pair_cpu_pct loop_cpu_pct atoms partner_entries steps neigh_builds"
parse() {
  awk '
    /^Loop time of/ { loop=$4; steps=$9; atoms=$12 }
    /% CPU use with/ { c=$1; sub(/%/,"",c); loopcpu=c }
    /^Pair +\|/ { n=split($0,f,"|"); gsub(/ /,"",f[3]); pair=f[3];
                  if (n>=7) { gsub(/ /,"",f[6]); paircpu=f[6] } else paircpu="null" }
    /total # of bonds =/ { partners=$NF }
    /^Neighbor list builds =/ { nb=$NF }
    END { printf "%s %s %s %s %s %s %s %s\n", loop, pair, paircpu, loopcpu, atoms, partners, steps, nb }
  ' "$1"
}

median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {if (NR%2) print a[(NR+1)/2]; else printf "%.9g\n", (a[NR/2]+a[NR/2+1])/2}'; }

# ---------------------------------------------------------------- bond-count variants (run 0)
log "LAMMPS $lammps_version ($LMP); bond-count check with run 0"
declare -A variant_hcut=(
  [inclusive_default]=""                       # input default: delta*(1+1e-7)
  [strict_hcut_0.17320508]="0.17320508"        # 8-digit delta: r=delta pairs fall outside
  [exact_double_no_margin]="0.17320508075688773"  # round-off decides each r=delta pair
)
variant_json=""
for v in inclusive_default strict_hcut_0.17320508 exact_double_no_margin; do
  extra=(-var steps 0)
  [[ -n "${variant_hcut[$v]}" ]] && extra+=(-var hcut "${variant_hcut[$v]}")
  OMP_NUM_THREADS=1 run_lmp "$work/count_$v.txt" "$LMP" "${base_args[@]}" "${extra[@]}"
  read -r _ _ _ _ a pe _ _ <<<"$(parse "$work/count_$v.txt")"
  hc="$(sed -n 's/.*hcut=\([^ ]*\).*/\1/p' "$work/count_$v.txt" | head -n1)"
  variant_json+="${variant_json:+, }\"$v\": {\"hcut\": $hc, \"atoms\": $a, \"partner_entries\": $pe, \"bonds_unordered\": $((pe / 2))}"
done

# ---------------------------------------------------------------- timed configurations
configs=(t1)
$omp_available && configs+=(t2)
[[ "$DIAGNOSTIC" == 1 ]] && configs+=(nc)
[[ -n "$MPI_RANKS" ]] && { command -v mpirun >/dev/null 2>&1 || die "BENCH_MPI_RANKS set but mpirun not found"; configs+=(mpi); }

cmd_for() {  # prints the command line of a configuration (for the record)
  case "$1" in
    t1)  echo "OMP_NUM_THREADS=1 $LMP ${base_args[*]} -var steps $STEPS" ;;
    t2)  echo "OMP_NUM_THREADS=2 $LMP ${base_args[*]} -var steps $STEPS -sf omp -pk omp 2" ;;
    nc)  echo "OMP_NUM_THREADS=1 $LMP ${base_args[*]} -var steps $STEPS -var contact no" ;;
    mpi) echo "OMP_NUM_THREADS=1 mpirun --allow-run-as-root -np $MPI_RANKS $LMP ${base_args[*]} -var steps $STEPS" ;;
  esac
}
run_cfg() {  # run_cfg CONFIG OUTFILE
  case "$1" in
    t1)  OMP_NUM_THREADS=1 run_lmp "$2" "$LMP" "${base_args[@]}" -var steps "$STEPS" ;;
    t2)  OMP_NUM_THREADS=2 run_lmp "$2" "$LMP" "${base_args[@]}" -var steps "$STEPS" -sf omp -pk omp 2 ;;
    nc)  OMP_NUM_THREADS=1 run_lmp "$2" "$LMP" "${base_args[@]}" -var steps "$STEPS" -var contact no ;;
    mpi) OMP_NUM_THREADS=1 run_lmp "$2" mpirun --allow-run-as-root -np "$MPI_RANKS" \
           "$LMP" "${base_args[@]}" -var steps "$STEPS" ;;
  esac
}

load_before="$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown)"
declare -A loops pairs paircpus loopcpus
pd_rates="" pd_ratios=""
atoms="" partners="" nbuilds_all=""
for ((r = 1; r <= REPS; r++)); do          # interleave configurations across repetitions
  for c in "${configs[@]}"; do
    log "rep $r/$REPS config $c: $(cmd_for "$c")"
    out="$work/run_${c}_$r.txt"
    run_cfg "$c" "$out"
    read -r l p pc lc a pe st nb <<<"$(parse "$out")"
    [[ "$st" == "$STEPS" ]] || die "LAMMPS ran $st steps, expected $STEPS"
    [[ -z "$atoms" ]] && atoms="$a" && partners="$pe"
    [[ "$a" == "$atoms" && "$pe" == "$partners" ]] || die "atom/bond count differs between runs"
    loops[$c]+="$l "; pairs[$c]+="$p "; paircpus[$c]+="$pc "; loopcpus[$c]+="$lc "
    nbuilds_all+="$nb "
    log "  loop $l s, pair $p s (pair %CPU $pc, loop %CPU $lc), neighbor builds $nb"
    if [[ -n "$PD" && "$c" == t1 ]]; then  # libpd right after, under the same load
      pd_rate="$("$PD" bench "$here/../../verification/scenes/model-a-benchmark.yaml" --threads 1 \
                  --steps 200 --repeats 1 --json | sed -n 's/.*"bond_updates_per_second": *\([^,}]*\).*/\1/p')"
      lmp_rate="$(awk -v b="$((pe / 2))" -v s="$STEPS" -v t="$l" 'BEGIN{printf "%.6g", b*s/t}')"
      pd_rates+="$pd_rate "; pd_ratios+="$(awk -v a="$pd_rate" -v b="$lmp_rate" 'BEGIN{printf "%.4g", a/b}') "
      log "  libpd $pd_rate bond updates/s, LAMMPS (loop) $lmp_rate -> ratio ${pd_ratios##* } (load $(cut -d' ' -f1 /proc/loadavg))"
    fi
  done
done
load_after="$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown)"

(( atoms == 5229 )) || log "WARNING: expected 5229 atoms, LAMMPS created $atoms"
bonds=$((partners / 2))
# shellcheck disable=SC2086
if awk -v m="$(median ${loops[t1]})" 'BEGIN{exit !(m < 5)}'; then
  log "WARNING: median loop time < 5 s; pass a larger STEPS for a steadier measurement"
fi

cfg_json() {
  local c="$1" ml mp mpc mlc cpus minp
  # shellcheck disable=SC2086
  ml="$(median ${loops[$c]})"; mp="$(median ${pairs[$c]})"
  # shellcheck disable=SC2086
  mpc="$(median ${paircpus[$c]})"; mlc="$(median ${loopcpus[$c]})"
  # per-run CPU seconds of the Pair section (wall x %CPU): robust against other processes
  cpus="$(paste -d' ' <(printf '%s\n' ${pairs[$c]}) <(printf '%s\n' ${paircpus[$c]}) |
          awk '$2 != "null" {printf "%.6g ", $1*$2/100}')"
  # shellcheck disable=SC2086
  minp="$(printf '%s\n' ${pairs[$c]} | sort -g | head -n1)"
  awk -v c="$c" -v ml="$ml" -v mp="$mp" -v mpc="$mpc" -v mlc="$mlc" -v b="$bonds" -v s="$STEPS" \
      -v L="${loops[$c]}" -v P="${pairs[$c]}" -v PC="${paircpus[$c]}" -v LC="${loopcpus[$c]}" \
      -v CS="$cpus" -v mcs="$( [[ -n "$cpus" ]] && median $cpus || echo null)" -v minp="$minp" \
      -v cmd="$(cmd_for "$c")" 'function arr(x,  n,i,a,o){n=split(x,a," ");o="[";for(i=1;i<=n;i++)o=o (i>1?", ":"") a[i];return o "]"}
    BEGIN {
      printf "{\"command\": \"%s\", ", cmd
      printf "\"median_loop_seconds\": %s, \"median_pair_seconds\": %s, ", ml, mp
      printf "\"bond_updates_per_second\": %.6g, ", b*s/mp
      printf "\"bond_updates_per_second_loop\": %.6g, ", b*s/ml
      printf "\"ns_per_bond_update_pair\": %.4g, ", mp/(b*s)*1e9
      printf "\"min_pair_seconds\": %s, \"bond_updates_per_second_best_pair\": %.6g, ", minp, b*s/minp
      printf "\"median_loop_cpu_percent\": %s, \"median_pair_cpu_percent\": %s, ", mlc, mpc
      if (mcs != "null") printf "\"median_pair_cpu_seconds\": %s, \"bond_updates_per_cpu_second_pair\": %.6g, ", mcs, b*s/mcs
      printf "\"runs_loop_seconds\": %s, \"runs_pair_seconds\": %s, ", arr(L), arr(P)
      printf "\"runs_loop_cpu_percent\": %s, \"runs_pair_cpu_percent\": %s, ", arr(LC), arr(PC)
      printf "\"runs_pair_cpu_seconds\": %s}", arr(CS)
    }'
}

threads_json="\"1\": $(cfg_json t1)"
$omp_available && threads_json+=", \"2\": $(cfg_json t2)"
mpi_json=""
diag_json=""
[[ "$DIAGNOSTIC" == 1 ]] && diag_json=", \"diagnostic_1_thread_bond_loop_only\": $(cfg_json nc)"
[[ -n "$MPI_RANKS" ]] && mpi_json=", \"mpi_ranks\": {\"$MPI_RANKS\": $(cfg_json mpi)}"
if $omp_available; then
  omp_note="OPENMP package with peri/pmb/omp present: 2-thread run uses -sf omp -pk omp 2"
else
  omp_note="this LAMMPS build has no OPENMP package (no peri/pmb/omp style): 2-thread run skipped"
fi
nb_max="$(printf '%s\n' $nbuilds_all | sort -g | tail -n1)"
pd_json=""
if [[ -n "$PD" ]]; then
  # shellcheck disable=SC2086
  pd_json=", \"libpd\": {\"command\": \"$PD bench verification/scenes/model-a-benchmark.yaml --threads 1 --steps 200 --repeats 1\", \"median_bond_updates_per_second\": $(median $pd_rates), \"median_ratio_to_lammps_loop\": $(median $pd_ratios), \"ratios\": [$(echo $pd_ratios | sed 's/ /, /g')]}"
fi

cat <<EOF
{
  "lammps_version": "$lammps_version",
  "debian_package_version": "${deb_version:-unknown}",
  "lmp": "$LMP",
  "input": "reports/lammps/model-a.in",
  "atoms": $atoms,
  "partner_entries": $partners,
  "bonds_unordered": $bonds,
  "bond_count_note": "fix PERI_NEIGH 'total # of bonds' = sum of npartner over atoms = partner entries (each bond stored in both atoms' lists); unordered = partner_entries/2; LAMMPS bonds a pair iff r^2 <= hcut^2",
  "bond_count_variants": {$variant_json},
  "steps": $STEPS,
  "timestep_s": 1e-6,
  "repetitions": $REPS,
  "neighbor_list_builds_max": ${nb_max:-null},
  "omp_available": $omp_available,
  "omp_note": "$omp_note",
  "nproc": $(nproc 2>/dev/null || echo null),
  "loadavg_before": "$load_before",
  "loadavg_after": "$load_after",
  "threads": {$threads_json}$mpi_json$diag_json$pd_json
}
EOF
