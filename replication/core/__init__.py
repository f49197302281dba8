"""The maths: rotations, the hand-eye operator, motions, statistics, validators and the solvers.

Nothing here knows about files, clocks or the paper's studies; :mod:`replication.rig` and
:mod:`replication.study` build on it. Modules: :mod:`.so3` (rotations and conversions),
:mod:`.kernels` (batched 3x3 / 4x4 linear algebra without a LAPACK call per matrix), :mod:`.checks`
(the ``check_*`` validators), :mod:`.handeye` (Sec. II as linear algebra), :mod:`.motions`
(validated pairs, ``K`` and observability), :mod:`.stats` (intervals and scores), :mod:`.solvers`
(every solver behind ``solve``). Conventions: ``docs/conventions.md``.
"""
