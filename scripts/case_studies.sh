#!/usr/bin/env bash
# Re-runs docs/case-studies.md: `hammerstein diagnose --follow` from a linear model on real
# records of ../shared/data (not shipped with the crate). Usage:
#   scripts/case_studies.sh [OUTDIR]      (release binary built by `cargo build --release`)
# Writes OUTDIR/<record>.txt (the step table and the final diagnosis), its time and report.
set -euo pipefail
cd "$(dirname "$0")/.."
D=${DATA:-../shared/data}
OUT=${1:-case-studies-out}
H=${H:-target/release/hammerstein}
mkdir -p "$OUT/cut"
cut_rows() { # file first last (1-based data rows, header kept) -> stdout
  awk -F, -v a="$2" -v b="$3" 'NR==1 || (NR-1>=a && NR-1<=b)' "$1"
}
cut_rows "$D/wiener_hammerstein_2009/WienerHammerBenchmark.csv" 5001 100000 > "$OUT/cut/wh_est.csv"
cut_rows "$D/wiener_hammerstein_2009/WienerHammerBenchmark.csv" 100001 188000 > "$OUT/cut/wh_test.csv"
cut_rows "$D/silverbox/SNLS80mV.csv" 40001 131072 > "$OUT/cut/sb_est.csv"
cut_rows "$D/silverbox/SNLS80mV.csv" 1 40000 > "$OUT/cut/sb_test.csv"
run() { # name, then diagnose arguments
  local name=$1; shift
  echo "== $name" >&2
  /usr/bin/time -f "%e s, %M KB" -o "$OUT/$name.time" \
    "$H" diagnose "$@" --follow --max-steps 6 --report "$OUT/$name-report" > "$OUT/$name.txt" 2>&1 || true
}
run mr-damper-ensaio01 "$D/labcontrol_mr_damper_sine/ensaio01.csv" --input vel_mm_s --output force_N --validate 0.3
run mr-damper-ensaio04 "$D/labcontrol_mr_damper_sine/ensaio04.csv" --input vel_mm_s --output force_N --validate 0.3
run piezo "$D/piezo_hysteresis_sine/piezo_150V_1Hz.csv" --input u_V --output y_um --validate 0.3
run emps "$D/emps/estimation.csv" --input force_N --output qm_m --validation-file "$D/emps/test_pulses.csv"
run wiener-hammerstein-2009 "$OUT/cut/wh_est.csv" --validation-file "$OUT/cut/wh_test.csv"
run silverbox "$OUT/cut/sb_est.csv" --validation-file "$OUT/cut/sb_test.csv"
run bouc-wen "$D/bouc_wen_simulated/train_multisine_5periods.csv" --validation-file "$D/bouc_wen_simulated/test_multisine.csv"
run f16 "$D/f16_gvt/F16Data_FullMSine_Level3.csv" --input force_N --output acc2 --validation-file "$D/f16_gvt/F16Data_FullMSine_Level2_Validation.csv"
run cascaded-tanks "$D/cascaded_tanks/estimation.csv" --validation-file "$D/cascaded_tanks/test.csv"
run daisy-dryer "$D/daisy_dryer/dryer.csv" --validate 0.3
