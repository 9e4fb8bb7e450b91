#!/usr/bin/env bash
# SLURM job array: 16 tasks share the sequence; each takes every 16th frame.
#   mkdir -p logs && sbatch examples/farm-slurm.sh
# A task that was killed (time limit, preemption, node failure) is resubmitted alone, by its ID;
# it does the same frames as in the array, and --skip-existing leaves the finished ones alone:
#   sbatch --array=5 examples/farm-slurm.sh        # several: --array=5,9
#SBATCH --job-name=splash
#SBATCH --array=0-15
#SBATCH --cpus-per-task=4
#SBATCH --time=02:00:00
#SBATCH --output=logs/splash-%A_%a.log
set -euo pipefail
# --shard auto/16 takes shard K = SLURM_ARRAY_TASK_ID mod 16 + 1, from the task's ID alone:
# --array=0-15 and --array=1-16 both give each shard to one task, and a resubmitted task keeps
# its shard. Arrays with a step (--array=0-30:2) or of more than 16 IDs are refused; pass K
# yourself there, e.g. --shard $((SLURM_ARRAY_TASK_ID / 2 + 1))/16. Other schedulers: pass
# the 1-based task index yourself, e.g.
#   PBS/Torque:  --shard $((PBS_ARRAY_INDEX + 1))/16    (with -J 0-15)
#   SGE:         --shard $((SGE_TASK_ID - SGE_TASK_FIRST + 1))/16
#   LSF:         --shard $LSB_JOBINDEX/16                (with -J "splash[1-16]")
srun splash recon sim/ --spacing 0.014 --cell r/2 --threads "$SLURM_CPUS_PER_TASK" \
    --shard auto/16 --skip-existing --log-format json -o mesh/
