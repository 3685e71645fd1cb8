#!/bin/bash
#SBATCH --job-name=ligwf-drum-study-analysis
#SBATCH --ntasks=1
#SBATCH --time=00:30:00
#SBATCH --partition=compute
#SBATCH --account=proj-42
#SBATCH --output=/scratch/alice/drum-study/slurm/logs/ligwf-drum-study-analysis_%j.out
#SBATCH --mem-per-cpu=2G
#SBATCH --constraint=avx2
# Written by ligwf 0.0.0-golden: analysis of the study /scratch/alice/drum-study
# after its case array has ended (submitted with --dependency=afterany).
set -eo pipefail
module load openmpi/4.1 liggghts/3.8.0
source /opt/ligwf/venv/bin/activate
ulimit -c 0
cd /scratch/alice/drum-study
/opt/ligwf/venv/bin/ligwf analyse /scratch/alice/drum-study
/opt/ligwf/venv/bin/ligwf report /scratch/alice/drum-study
