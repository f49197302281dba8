"""The replication of the paper: its numbers and claims, the ledger, one support module per
notebook.

Built on :mod:`replication.rig` and :mod:`replication.core`; nothing below imports it. Modules:
:mod:`.paper` (the published numbers, ``data/paper/``), :mod:`.ledger` (claims and verdicts),
:mod:`.simulation` (Sec. III-A's generator), :mod:`.recalibration` (02's online re-calibration
claim), :mod:`.table1` (notebook 03), :mod:`.fig5` (04), :mod:`.lab` and :mod:`.table2` (05),
:mod:`.baselines` and :mod:`.convexity` (06; the latter also 01's section 3d), :mod:`.real_study`
(07), :mod:`.live_study` and :mod:`.vins_rule` (08: VINS-Mono's rule, the baseline its replays
compare with), :mod:`.figures` and :mod:`.notebook` (the notebooks' figures and setup).
"""
