#!/bin/bash
#SBATCH --job-name=ligwf-drum-study
#SBATCH --array=0-35%8
#SBATCH --ntasks=4
#SBATCH --time=1-02:00:00
#SBATCH --partition=compute
#SBATCH --account=proj-42
#SBATCH --output=/scratch/alice/drum-study/slurm/logs/ligwf-drum-study_%A_%a.out
#SBATCH --mem-per-cpu=2G
#SBATCH --constraint=avx2
# Written by ligwf 0.0.0-golden: one array task per case of the study
# /scratch/alice/drum-study (task id = case index in study.json; 36 case(s)).
set -eo pipefail
module load openmpi/4.1 liggghts/3.8.0
source /opt/ligwf/venv/bin/activate
ulimit -c 0
export LIGWF_MPIRUN=srun
export LIGWF_MPIRUN_ARGS=--mpi=pmix
cd /scratch/alice/drum-study
echo "ligwf: case ${SLURM_ARRAY_TASK_ID} of array ${SLURM_ARRAY_JOB_ID} on $(hostname) with ${SLURM_NTASKS:-1} task(s) on ${SLURM_JOB_NUM_NODES:-1} node(s): ${SLURM_JOB_NODELIST:-$(hostname)}"
exec /opt/ligwf/venv/bin/ligwf run-case /scratch/alice/drum-study --index "$SLURM_ARRAY_TASK_ID" --np "${SLURM_NTASKS:-1}"
