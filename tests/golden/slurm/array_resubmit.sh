#!/bin/bash
#SBATCH --job-name=ligwf-drum-study
#SBATCH --array=1,4-6,9%2
#SBATCH --ntasks=1
#SBATCH --time=30
#SBATCH --output=/scratch/alice/drum-study/slurm/logs/ligwf-drum-study_%A_%a.out
# Written by ligwf 0.0.0-golden: one array task per case of the study
# /scratch/alice/drum-study (task id = case index in study.json; 5 case(s)).
set -eo pipefail
cd /scratch/alice/drum-study
echo "ligwf: case ${SLURM_ARRAY_TASK_ID} of array ${SLURM_ARRAY_JOB_ID} on $(hostname) with ${SLURM_NTASKS:-1} task(s) on ${SLURM_JOB_NUM_NODES:-1} node(s): ${SLURM_JOB_NODELIST:-$(hostname)}"
exec /opt/ligwf/venv/bin/ligwf run-case /scratch/alice/drum-study --index "$SLURM_ARRAY_TASK_ID" --np "${SLURM_NTASKS:-1}"
