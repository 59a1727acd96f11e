#!/usr/bin/env bash
# Issue 34's scaling figures on a many-core machine, in one call of about
# 7 minutes on a 16-core Xeon (estimated from the rates of 2026-11-26):
#   1. the 10⁴ fragmenting impact at 1, 2, 4, 8 and 16 threads (default
#      duration; E(n) against 1 thread);
#   2. late paper-scale caving steps from a checkpoint at 1–16 threads
#      (make it with `python examples/block_caving.py --until 1.25
#      --threads 2`, 10.5 min on a 2-core Intel Xeon VM, 47 MB);
#   3. the 10⁵ impact to 2×10⁻⁴ s after contact (4 960 steps, 13 894
#      cracks: fragmentation starting; 61 s at 2 threads on that VM)
#      at 16 threads first, then 1, 2, 4, 8 (its E(n) column is against
#      16 threads, the first listed: E(n) against 1 is rate(n)/(n rate(1))).
# Each part has its own time limit, and writes its table to OUT (default
# scaling_output) as it goes.
# Usage: benchmarks/scaling.sh CHECKPOINT [OUT]
set -uo pipefail
ckpt=${1:?usage: benchmarks/scaling.sh CHECKPOINT [OUT]}
out=${2:-scaling_output}
mkdir -p "$out"
export PYTHONUNBUFFERED=1 OPENBLAS_NUM_THREADS=1
here=$(dirname "$0")
{ nproc; lscpu | grep -iE "model name|^L3|NUMA node\(|Thread"; } | tee "$out/machine.txt"
timeout 240 python3 "$here/fracture_impact.py" --elements 1e4 --threads 1 2 4 8 16 | tee "$out/impact_1e4.txt"
timeout 150 python3 "$here/caving_late.py" "$ckpt" --threads 1 2 4 8 16 --steps 400 | tee "$out/caving_late.txt"
timeout 200 python3 "$here/fracture_impact.py" --elements 1e5 --threads 16 1 2 4 8 --duration 2e-4 \
    | tee "$out/impact_1e5.txt"
