#!/bin/bash
cd /work/wt-omis
export OPENBLAS_NUM_THREADS=1
for P in /work/wt-omis /tmp/omis_base; do
  n=$(basename $P)
  PYTHONPATH=$P nice .venv/bin/python scratch/omis_probe_oneaxis.py 69100 10 0.015 25 > scratch/out/oneaxis_$n.out 2>&1
done
