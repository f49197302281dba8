#!/bin/bash
cd /work/wt-rt6/scratch/rt6
export OPENBLAS_NUM_THREADS=1
PYTHONPATH=/work/wt-omis nice /work/wt-omis/.venv/bin/python probe_online_mis.py 66000 10 0.01 0.03 > /work/wt-omis/scratch/out/after_66000_mu1_3.out 2>&1
