#!/bin/bash
# Submits the shards of examples/slurm/sweep-array.sh as an array of N tasks and the
# merge as a job that starts when all of them succeeded.  Usage: submit.sh [N]
set -euo pipefail
N=${1:-8}
here=$(dirname "$0")
jobid=$(sbatch --parsable --array=1-"$N" "$here/sweep-array.sh")
sbatch --dependency=afterok:"$jobid" --export=ALL,MERGE=1 "$here/sweep-array.sh"
