"""Table I (Sec. III-A) and the studies of ``notebooks/03_table1_monte_carlo.ipynb``.

:mod:`.table`: per-iteration errors of each method, the table, the comparison with the paper in
standard errors (its three printed decimals taken as a bound), convergence measures with bootstrap
intervals. :mod:`.grid`: the grid over the unstated settings (section 2). :mod:`.study`: the
notebook's other studies, section by section. :mod:`.claims`, :mod:`.sqp_claims` and
:mod:`.cell_claims`: the ledger records, one function per claim, called from the cells that measure
their numbers. :mod:`.minimum`: SQP's failures at the paper's and SLSQP's default caps, the two-step
iterates against the certified minimum. SQP appears once per named variant
(:data:`replication.core.solvers.SQP_VARIANTS`), as columns ``"optimization (analytic)"`` etc.; each
is compared with the paper's single "Optimization" column. Table II sits beside it in
:mod:`replication.study.table2`.
"""
from .cell_claims import *  # noqa: F403
from .cell_claims import __all__ as _cell_claims_names
from .claims import *  # noqa: F403
from .claims import __all__ as _claims_names
from .grid import *  # noqa: F403
from .grid import __all__ as _grid_names
from .minimum import *  # noqa: F403
from .minimum import __all__ as _minimum_names
from .sqp_claims import *  # noqa: F403
from .sqp_claims import __all__ as _sqp_claims_names
from .study import *  # noqa: F403
from .study import __all__ as _study_names
from .table import *  # noqa: F403
from .table import __all__ as _table_names

__all__ = [*_table_names, *_grid_names, *_study_names, *_claims_names, *_sqp_claims_names, *_cell_claims_names,
           *_minimum_names]
