"""Table I (Sec. III-A) and the studies of ``notebooks/03_table1_monte_carlo.ipynb``.

:mod:`.table`: per-iteration errors of each method, the table, the comparison with the paper in standard
errors, convergence measures with bootstrap intervals. :mod:`.study`: the notebook's studies, section by
section. :mod:`.claims`: the ledger records of its section 5. SQP appears once per named variant
(:data:`replication.core.solvers.SQP_VARIANTS`), as columns ``"optimization (analytic)"`` etc.; each is compared
with the paper's single "Optimization" column.
Table II sits beside it in :mod:`replication.study.table2`.
"""
from .claims import *  # noqa: F403
from .claims import __all__ as _claims_names
from .study import *  # noqa: F403
from .study import __all__ as _study_names
from .table import *  # noqa: F403
from .table import __all__ as _table_names

__all__ = [*_table_names, *_study_names, *_claims_names]
