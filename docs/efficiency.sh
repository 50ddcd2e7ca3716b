#!/usr/bin/env bash
# Parallel efficiency of `phototaxis sweep`: wall time of equal trials on 1 vs 2 local workers.
# Usage: docs/efficiency.sh [TRIALS=4] [STEPS=5000]. Run it on an otherwise idle machine.
set -euo pipefail
trials=${1:-4}; steps=${2:-5000}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
run() {  # $1 = workers; prints wall seconds
  rm -rf "$tmp/w$1"
  local s e; s=$(date +%s.%N)
  phototaxis sweep --cases square --trials "$trials" --steps "$steps" --workers "$1" \
    --no-progress --no-report --out "$tmp/w$1" >/dev/null 2>&1
  e=$(date +%s.%N); python3 -c "print(round($e - $s, 2))"
}
one=(); two=()
for _ in 1 2; do one+=("$(run 1)"); two+=("$(run 2)"); done   # interleaved, so load drift hits both
python3 - "${one[@]}" "${two[@]}" <<'PY'
import sys
one, two = list(map(float, sys.argv[1:3])), list(map(float, sys.argv[3:5]))
print(f"1 worker: {one} s   2 workers: {two} s   ratio (2 / 1, best of each): {min(two) / min(one):.2f}")
PY
