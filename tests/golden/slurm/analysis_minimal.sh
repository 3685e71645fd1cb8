#!/bin/bash
#SBATCH --job-name=ligwf-drum-study-analysis
#SBATCH --ntasks=1
#SBATCH --output=/scratch/alice/drum-study/slurm/logs/ligwf-drum-study-analysis_%j.out
# Written by ligwf 0.0.0-golden: analysis of the study /scratch/alice/drum-study
# after its case array has ended (submitted with --dependency=afterany).
set -eo pipefail
cd /scratch/alice/drum-study
/opt/ligwf/venv/bin/ligwf analyse /scratch/alice/drum-study
