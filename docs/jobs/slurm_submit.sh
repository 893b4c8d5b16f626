#!/bin/bash
# Submits the two Slurm jobs: the simulation, then the render array once it succeeded.
#
#   SCENE=/shared/scene.json WORK=/shared/work FRAMES=0-999 CHUNK=100 TASKS=10 \
#       docs/jobs/slurm_submit.sh
#
# TASKS must be at least the number of chunks, ceil(frames listed / CHUNK); a larger
# array does no harm (its extra tasks render nothing and succeed). Array ids are the
# chunk indices, so the array starts at 0.
set -euo pipefail
: "${SCENE:?the scene file}" "${WORK:?a shared folder}" "${FRAMES:?e.g. 0-999}"
: "${CHUNK:?frames a render task}" "${TASKS:?render tasks}"
export SCENE WORK FRAMES CHUNK
here="$(dirname "$0")"
mkdir -p logs

sim="$(sbatch --parsable --export=ALL "$here/slurm_simulate.sbatch")"
sim="${sim%%;*}" # --parsable prints "id" or "id;cluster"
render="$(sbatch --parsable --export=ALL --dependency="afterok:$sim" \
    --array="0-$((TASKS - 1))" "$here/slurm_render.sbatch")"
echo "simulate: job ${sim}; render: array job ${render%%;*} (tasks 0-$((TASKS - 1)))"
