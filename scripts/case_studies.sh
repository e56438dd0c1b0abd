#!/usr/bin/env bash
# Re-runs docs/case-studies.md: `hammerstein diagnose --follow` (default options: each step
# confirmed on held-back parts of the training record) from a linear model on the ten real
# records of ../shared/data (not shipped with the crate). Usage:
#   scripts/case_studies.sh [OUTDIR]      (release binary built by `cargo build --release`)
#   ONLY="piezo emps" scripts/case_studies.sh OUTDIR     (some records only)
# Writes OUTDIR/<record>.json (`diagnose --json`: every step, its check, the final model), its
# wall time, CPU time and peak memory (<record>.time), stderr (<record>.err), one HTML report per record,
# and OUTDIR/records.tsv (name, training file, input column, validation fraction, command), which
# scripts/check_case_studies.py reads.
set -euo pipefail
cd "$(dirname "$0")/.."
D=${DATA:-../shared/data}
OUT=${1:-case-studies-out}
H=${H:-target/release/hammerstein}
ONLY=${ONLY:-}
mkdir -p "$OUT/cut"
cut_rows() { # file first last (1-based data rows, header kept) -> stdout
  awk -F, -v a="$2" -v b="$3" 'NR==1 || (NR-1>=a && NR-1<=b)' "$1"
}
cut_rows "$D/wiener_hammerstein_2009/WienerHammerBenchmark.csv" 5001 100000 > "$OUT/cut/wh_est.csv"
cut_rows "$D/wiener_hammerstein_2009/WienerHammerBenchmark.csv" 100001 188000 > "$OUT/cut/wh_test.csv"
cut_rows "$D/silverbox/SNLS80mV.csv" 40001 131072 > "$OUT/cut/sb_est.csv"
cut_rows "$D/silverbox/SNLS80mV.csv" 1 40000 > "$OUT/cut/sb_test.csv"
touch "$OUT/records.tsv"
run() { # name, training file, input column ("" = the first), validation fraction ("" = a file),
        # then the other diagnose arguments
  local name=$1 file=$2 input=$3 validate=$4; shift 4
  if [ -n "$ONLY" ] && [[ " $ONLY " != *" $name "* ]]; then return 0; fi
  echo "== $name" >&2
  local args=("$file")
  [ -n "$input" ] && args+=(--input "$input")
  [ -n "$validate" ] && args+=(--validate "$validate")
  /usr/bin/time -f "%e s, %U s user, %S s sys, %M KB" -o "$OUT/$name.time" \
    "$H" diagnose "${args[@]}" "$@" --follow --report "$OUT/$name-report" --json \
    > "$OUT/$name.json" 2> "$OUT/$name.err" || true
  grep -v "^$name	" "$OUT/records.tsv" > "$OUT/records.tsv.new" || true
  printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$file" "${input:-u}" "$validate" \
    "hammerstein diagnose ${args[*]} $* --follow --report $OUT/$name-report --json" >> "$OUT/records.tsv.new"
  mv "$OUT/records.tsv.new" "$OUT/records.tsv"
}
run mr-damper-ensaio01 "$D/labcontrol_mr_damper_sine/ensaio01.csv" vel_mm_s 0.3 --output force_N
run mr-damper-ensaio04 "$D/labcontrol_mr_damper_sine/ensaio04.csv" vel_mm_s 0.3 --output force_N
run cascaded-tanks "$D/cascaded_tanks/estimation.csv" "" "" --validation-file "$D/cascaded_tanks/test.csv"
run daisy-dryer "$D/daisy_dryer/dryer.csv" "" 0.3
run f16 "$D/f16_gvt/F16Data_FullMSine_Level3.csv" force_N "" --output acc2 --validation-file "$D/f16_gvt/F16Data_FullMSine_Level2_Validation.csv"
run wiener-hammerstein-2009 "$OUT/cut/wh_est.csv" "" "" --validation-file "$OUT/cut/wh_test.csv"
run silverbox "$OUT/cut/sb_est.csv" "" "" --validation-file "$OUT/cut/sb_test.csv"
run bouc-wen "$D/bouc_wen_simulated/train_multisine_5periods.csv" "" "" --validation-file "$D/bouc_wen_simulated/test_multisine.csv"
run emps "$D/emps/estimation.csv" force_N "" --output qm_m --validation-file "$D/emps/test_pulses.csv"
run piezo "$D/piezo_hysteresis_sine/piezo_150V_1Hz.csv" u_V 0.3 --output y_um
