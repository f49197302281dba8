#!/bin/bash
# after (this branch) and before (HEAD of main at branch point) on found, fresh and control seeds
cd /work/wt-rt6/scratch/rt6
O=/work/wt-omis/scratch/out
mkdir -p $O
PY=/work/wt-omis/.venv/bin/python
export OPENBLAS_NUM_THREADS=1
PYTHONPATH=/work/wt-omis nice $PY probe_online_mis.py 66000 10 0.015 > $O/after_66000.out 2>&1
PYTHONPATH=/work/wt-omis nice $PY probe_online_mis.py 67000 20 0.015 > $O/after_67000.out 2>&1
PYTHONPATH=/work/wt-omis nice $PY probe_online_mis.py 68600 30 0.015 0.0 > $O/after_68600.out 2>&1
PYTHONPATH=/tmp/omis_base nice $PY probe_online_mis.py 68600 30 0.015 0.0 > $O/before_68600.out 2>&1
