#!/bin/bash
#SBATCH --job-name=ligwf-drum-study
#SBATCH --array=0
#SBATCH --ntasks=119
#SBATCH --nodes=2
#SBATCH --time=12:00:00
#SBATCH --partition=compute
#SBATCH --output=/scratch/alice/drum-study/slurm/logs/ligwf-drum-study_%A_%a.out
# Written by ligwf 0.0.0-golden: one array task per case of the study
# /scratch/alice/drum-study (task id = case index in study.json; 1 case(s)).
set -eo pipefail
export OMPI_MCA_btl_tcp_if_include=10.0.0.0/8
export LIGWF_MPIRUN=mpirun
cd /scratch/alice/drum-study
echo "ligwf: case ${SLURM_ARRAY_TASK_ID} of array ${SLURM_ARRAY_JOB_ID} on $(hostname) with ${SLURM_NTASKS:-1} task(s) on ${SLURM_JOB_NUM_NODES:-1} node(s): ${SLURM_JOB_NODELIST:-$(hostname)}"
exec /opt/ligwf/venv/bin/ligwf run-case /scratch/alice/drum-study --index "$SLURM_ARRAY_TASK_ID" --np "${SLURM_NTASKS:-1}"
