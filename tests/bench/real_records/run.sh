#!/bin/bash
# Reruns the "Real records" table of docs/diagnose.md: rig identify on one part of each record,
# rig diagnose on another.
# Usage: RIG=build/bin/rig bash tests/bench/real_records/run.sh [OUT]   (OUT/<name>/, summary.md)
RIG=$(realpath "${RIG:-build/bin/rig}")
RIG_SHARED_DIR=${RIG_SHARED_DIR:-/work/shared}
D=$RIG_SHARED_DIR/data/nonlinear_benchmarks
Y=$RIG_SHARED_DIR/data/daisy
OUT=$(realpath -m "${1:-/tmp/real-records}")
mkdir -p $OUT

excerpt() {  # FILE COL_IN COL_OUT FROM TO > OUT.csv  (1-based columns; TO = -1: the end)
  case $1 in *.dat) fs=' '; skip=0;; *) fs=','; skip=1;; esac
  awk -F"$fs" -v i="$2" -v o="$3" -v a="$4" -v b="$5" -v s="$skip" 'BEGIN { print "u,y" }
    FNR > s { n = FNR - 1 - s; if (n >= a && (b < 0 || n < b) && $i != "") print $i "," $o }' "$1"
}
# .dat files: whitespace-separated, may have leading blanks -> awk -F' ' is default splitting (ok)

# rec NAME DT  EST_FILE CI CO FROM TO  VAL_FILE CI CO FROM TO  [FALLBACK identify options...]
rec() {
  local name=$1 dt=$2; shift 2
  local w=$OUT/$name; rm -rf $w; mkdir -p $w
  excerpt $1 $2 $3 $4 $5 > $w/est.csv
  excerpt $6 $7 $8 $9 ${10} > $w/val.csv
  shift 10
  echo "== $name: identify" | tee $w/log.txt
  ( cd $w; $RIG identify --recording est.csv --dt $dt --out id --force ) >> $w/log.txt 2>&1
  local rc=$?; echo "identify rc=$rc" >> $w/log.txt; echo "default" > $w/id_used.txt
  if [ $rc -ne 0 ] && [ $# -gt 0 ]; then
    for opts in "$@"; do
      echo "== $name: identify fallback: $opts" >> $w/log.txt
      ( cd $w; $RIG identify --recording est.csv --dt $dt --out id --force $opts ) >> $w/log.txt 2>&1
      rc=$?; echo "identify ($opts) rc=$rc" >> $w/log.txt
      if [ $rc -eq 0 ]; then echo "$opts" > $w/id_used.txt; break; fi
    done
  fi
  if [ -f $w/id/model.json ]; then
    echo "== $name: diagnose" >> $w/log.txt
    local t0=$(date +%s.%N)
    ( cd $w; $RIG diagnose --recording val.csv --dt $dt --model id/model.json --out dg --force ) >> $w/log.txt 2>&1
    echo "diagnose rc=$? wall=$(echo "$(date +%s.%N) - $t0" | bc)" >> $w/log.txt
  else
    echo "no model.json; diagnose not run" >> $w/log.txt
  fi
}

SB=$D/silverbox
rec wh2009   $(echo "1/51200" | bc -l) $D/wiener_hammerstein_2009/WienerHammerBenchmark.csv 1 2 5200 25200  $D/wiener_hammerstein_2009/WienerHammerBenchmark.csv 1 2 105200 125200
rec sb_arrow 0.0016384 $SB/SNLS80mV.csv 1 2 40650 60650  $SB/SNLS80mV.csv 1 2 100 40575
rec sb_msine 0.0016384 $SB/SNLS80mV.csv 1 2 40650 60650  $SB/SNLS80mV.csv 1 2 105712 127400
rec sb_schroeder 0.0016384 $SB/Schroeder80mV.csv 3 4 10584 18776  $SB/Schroeder80mV.csv 3 4 18776 26968
rec tanks    4    $D/cascaded_tanks/dataBenchmark.csv 1 3 0 -1  $D/cascaded_tanks/dataBenchmark.csv 2 4 0 -1
rec ce8_prbs 0.02 $D/coupled_electric_drives/DATAPRBS.csv 2 1 0 -1  $D/coupled_electric_drives/DATAPRBS.csv 4 3 0 -1 "--order 1/0" "--order 1/0 --delay 0" "--method mmfm --order 1/0" "--rows all --order 1/0"
rec ce8_unif 0.02 $D/coupled_electric_drives/DATAUNIF.csv 1 3 0 400  $D/coupled_electric_drives/DATAUNIF.csv 2 4 0 -1 "--order 4/2" "--order 4/2 --delay 0" "--order 2/0"
rec ce8_unif400 0.02 $D/coupled_electric_drives/DATAUNIF.csv 1 3 0 400  $D/coupled_electric_drives/DATAUNIF.csv 2 4 0 400 "--order 4/2" "--order 4/2 --delay 0" "--order 2/0"
rec emps     0.001 $D/emps/DATA_EMPS.csv 2 3 0 -1  $D/emps/DATA_EMPS_PULSES.csv 2 3 0 -1 "--order 2/1" "--order 2/1 --delay 0" "--order 2/1 --method mmfm"
rec f16_l7   0.0025 $D/f16_gvt/F16Data_FullMSine_Level1.csv 1 4 0 16384  $D/f16_gvt/F16Data_FullMSine_Level7.csv 1 4 0 16384
rec f16_oddval 0.0025 $D/f16_gvt/F16Data_FullMSine_Level1.csv 1 4 0 16384  $D/f16_gvt/F16Data_SpecialOddMSine_Level1_Validation.csv 1 4 0 16384
rec boucwen  $(echo "1/750" | bc -l) $D/bouc_wen_sim/val_multisine.csv 1 2 0 4096  $D/bouc_wen_sim/val_multisine.csv 1 2 4096 -1
rec dryer    0.08 $Y/dryer.dat 1 2 0 500  $Y/dryer.dat 1 2 500 1000
rec heating  2    $Y/heating_system.dat 2 3 0 400  $Y/heating_system.dat 2 3 400 801 "--order 1/0" "--order 1/0 --delay 0"
rec exchanger 1   $Y/exchanger.dat 2 3 0 2000  $Y/exchanger.dat 2 3 2000 4000 "--order 1/0" "--order 1/0 --delay 0" "--lags 32 --order 1/0"
rec exchanger_auto 1   $Y/exchanger.dat 2 3 0 2000  $Y/exchanger.dat 2 3 2000 4000 "--lags 32"
rec cdplayer 1    $Y/CD_player_arm.dat 1 3 0 1024  $Y/CD_player_arm.dat 1 3 1024 2048
rec thermic  1    $Y/thermic_res_wall.dat 1 3 0 840  $Y/thermic_res_wall.dat 1 3 840 1680 "--order 1/0" "--order 1/0 --delay 0" "--lags 32 --order 1/0"
rec thermic_auto 1    $Y/thermic_res_wall.dat 1 3 0 840  $Y/thermic_res_wall.dat 1 3 840 1680 "--lags 32"
rec robot_arm 1   $Y/robot_arm.dat 1 2 0 512  $Y/robot_arm.dat 1 2 512 1024 "--order 2/1" "--order 2/0" "--order 1/0"
rec winding  0.1  $Y/winding.dat 1 6 0 1250  $Y/winding.dat 1 6 1250 2500 "--order 2/1" "--order 2/0" "--order 1/0"
rec ballbeam 0.1  $Y/ballbeam.dat 1 2 0 500  $Y/ballbeam.dat 1 2 500 1000
rec flutter  1    $Y/flutter.dat 1 2 0 512  $Y/flutter.dat 1 2 512 1024 "--lags 128"
rec powerplant 1228.8 $Y/powerplant.dat 2 7 0 100  $Y/powerplant.dat 2 7 100 200 "--order 1/0"

# Lag-window scan used to find the fallbacks above (gate = cross-correlation peak >= 5 sd and
# enough excited frequencies; only --lags changes it):
#   for L in 8 16 24 32 48 64 128; do $RIG identify --recording $OUT/<rec>/est.csv --dt <dt> --lags $L --out x --force; done
# EMPS, heating, CE8 PRBS/uniform, robot_arm, winding refuse at every --lags/--order/--method/--rows.

# EMPS, extra (NOT rig identify): the identify() model quoted in docs/diagnose.md finding 1,
# 0.439/(s^2 + 6.77 s + 0.877), written by hand, then rig diagnose on the pulses record.
w=$OUT/emps_docsmodel; rm -rf $w; mkdir -p $w
cat > $w/model.json <<'JSON'
{"type": "tf", "num": [0.439], "den": [1.0, 6.77, 0.877], "delay_s": 0.0, "input": "u", "output": "y",
 "structure": "2/0 hand-written from docs finding 1", "method": "none", "source": "docs/diagnose.md"}
JSON
( cd $w; $RIG diagnose --recording $OUT/emps/val.csv --dt 0.001 --model model.json --out dg --force ) > $w/log.txt 2>&1
echo "diagnose rc=$?" >> $w/log.txt

/usr/bin/python3 "$(dirname "$0")/summarize.py" "$OUT" > "$OUT/summary.md"
echo "summary: $OUT/summary.md"
