#!/bin/bash
cd /work/wt-omis
export OPENBLAS_NUM_THREADS=1
PYTHONPATH=/work/wt-omis nice .venv/bin/python scratch/omis_real.py 0.0 0.015 0.01 > scratch/out/real_after.out 2>&1
PYTHONPATH=/tmp/omis_base nice .venv/bin/python scratch/omis_real.py 0.0 0.015 > scratch/out/real_before.out 2>&1
