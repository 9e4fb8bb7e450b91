#!/usr/bin/env bash
# SLURM job array: 16 tasks share the sequence; task i takes every 16th frame.
#   mkdir -p logs && sbatch examples/farm-slurm.sh
# A task that was killed (time limit, preemption) is resubmitted with the same command:
#   sbatch --array=5 examples/farm-slurm.sh     # --skip-existing finishes its frames
#SBATCH --job-name=splash
#SBATCH --array=0-15
#SBATCH --cpus-per-task=4
#SBATCH --time=02:00:00
#SBATCH --output=logs/splash-%A_%a.log
set -euo pipefail
# --shard auto/16 reads SLURM_ARRAY_TASK_ID minus SLURM_ARRAY_TASK_MIN, so --array=1-16 works
# as well as 0-15. Other schedulers: pass the 1-based task index yourself, e.g.
#   PBS/Torque:  --shard $((PBS_ARRAY_INDEX + 1))/16    (with -J 0-15)
#   SGE:         --shard $((SGE_TASK_ID - SGE_TASK_FIRST + 1))/16
#   LSF:         --shard $LSB_JOBINDEX/16                (with -J "splash[1-16]")
srun splash recon sim/ --spacing 0.014 --cell r/2 --threads "$SLURM_CPUS_PER_TASK" \
    --shard auto/16 --skip-existing --log-format json -o mesh/
