#!/bin/bash
cd /work/wt-omis
export OPENBLAS_NUM_THREADS=1
PYTHONPATH=/work/wt-omis nice .venv/bin/python scratch/omis_probe_oneaxis.py 69100 10 0.015 45 > scratch/out/oneaxis_45_after.out 2>&1 &
PYTHONPATH=/tmp/omis_base nice .venv/bin/python scratch/omis_probe_oneaxis.py 69100 10 0.015 45 > scratch/out/oneaxis_45_before.out 2>&1
wait
