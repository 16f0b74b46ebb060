#!/usr/bin/env bash
# Submits a split render to Slurm: an array of N parts, and a merge job that runs only if
# every part succeeded (--dependency=afterok). Prints the merge job's id.
#
#   deploy/slurm/submit-parts.sh N SCENE PARTS_DIR RESULT [render options...]
#
# Extra sbatch options (partition, account, time limit, GPUs) go in SBATCH_* environment
# variables, which sbatch reads: SBATCH_PARTITION=gpu SBATCH_TIMELIMIT=1:00:00 ...
set -euo pipefail
n=${1:?usage: submit-parts.sh N SCENE PARTS_DIR RESULT [render options]}
scene=${2:?}; out=${3:?}; result=${4:?}
shift 4
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
array=$(SCENE="$scene" OUT="$out" sbatch --parsable --array="0-$((n - 1))" \
  --chdir="$PWD" --output="$out/part-%a.log" "$here/parts.sbatch" "$@")
array=${array%%;*}
OUT="$out" RESULT="$result" sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --chdir="$PWD" --output="$out/merge.log" "$here/merge.sbatch"
