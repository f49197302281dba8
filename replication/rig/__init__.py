"""Calibrating a real rig: streams and data files, time association, ``calibrate``, its verdict and
report, online.

Built on :mod:`replication.core`; the paper's studies (:mod:`replication.study`) build on it.
Modules: data (:mod:`.streams`, :mod:`.datafile`, :mod:`.realdata`, :mod:`.fetch`), time
(:mod:`.association`, its numerical core :mod:`.offset_search`), the calibration
(:mod:`.calibration`, :mod:`.poses`, :mod:`.solve_and_judge`), its judges (:mod:`.quality`,
:mod:`.diagnose`, :mod:`.changepoint`), what it returns (:mod:`.report`, :mod:`.figure`), online
(:mod:`.online`, :mod:`.online_events`, :mod:`.live`). Its commands live in :mod:`replication.cli`.
"""
