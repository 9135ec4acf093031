#!/bin/bash
# One plain, large gensim case per effect (and two nulls) with a PRBS bias instead of the
# Gaussian one, diagnosed by rig; prints each verdict and the chosen hypothesis. No oracle
# is run: these are the large plain cases, all detectable with the Gaussian bias.
#   tests/bench/gensim/prbs_plain.sh RIG SEED OUT      (~3 min)
set -euo pipefail
RIG=$(realpath "$1"); SEED=$2; OUT=$3
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
right=0; total=0
for e in dead_time extra_lag sensor_lag gain_change rate_limit saturation deadband backlash \
         hysteresis static_nonlinearity resonance load_damping periodic_disturbance drift \
         ac_coupling none none; do
  total=$((total + 1))
  d="$OUT/s$SEED-$total-$e"
  [ -f "$d/recording.csv" ] || /usr/bin/python3 "$HERE/cases.py" --effect "$e" --concealment plain \
      --seed $((SEED * 100 + total)) --excitation prbs --out "$d" > /dev/null
  "$RIG" diagnose --recording "$d/recording.csv" --model "$d/model.json" --out "$d/diag" \
      --force > /dev/null 2>&1 || true
  line=$(/usr/bin/python3 - "$d" "$e" <<'PY'
import json, sys
r = json.load(open(sys.argv[1] + "/diag/report.json"))
want, got = sys.argv[2], r["verdict"]
lag = {"extra_lag", "sensor_lag"}
ok = got == want or (want in lag and got in lag) or (want == "hysteresis" and got == "backlash")
h = r["hypotheses"][r["chosen"]] if isinstance(r.get("chosen"), int) else None
what = "" if h is None else " + ".join(f"{x['effect']}@{x['place']}" for x in h["effects"])
print(f"{'ok ' if ok else 'BAD'} {want:22s} -> {got:22s} {what}")
PY
)
  echo "$line"
  case "$line" in ok*) right=$((right + 1));; esac
done
echo "PRBS seed $SEED: $right/$total right"
