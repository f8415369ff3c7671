#!/bin/bash
# One mtsim study as a Slurm job array: task K of N runs shard K/N, and a dependent job
# joins the shards with `mtsim merge` (byte-identical to the single-machine run).
#
#   sbatch --array=1-8 examples/slurm/sweep-array.sh          # the shards
#   sbatch --dependency=afterok:<jobid> --export=ALL,MERGE=1 examples/slurm/sweep-array.sh
#
# or submit both at once with examples/slurm/submit.sh. The working folder must be on a
# file system every node sees; mtsim must be on PATH (or set MTSIM).
#SBATCH --job-name=mtsim-sweep
#SBATCH --cpus-per-task=4
#SBATCH --time=01:00:00
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail

MTSIM=${MTSIM:-mtsim}
OUT=${OUT:-study}
STUDY=(sweep scenarios/cone-15-10.toml --vary center_y --from -30 --to -15 --step 0.1)

if [[ "${MERGE:-0}" == 1 ]]; then
    "$MTSIM" merge "$OUT"/shards/*.shard-*-of-*.json -o "$OUT"
else
    : "${SLURM_ARRAY_TASK_ID:?submit with --array=1-N}"
    : "${SLURM_ARRAY_TASK_COUNT:?submit with --array=1-N}"
    # rayon uses the task's CPUs.
    export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
    "$MTSIM" "${STUDY[@]}" --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}" -o "$OUT/shards"
fi
