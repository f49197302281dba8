"""Is problem (8)-(10) convex? Notebook 06, section 4 (and the count of notebook 01, section 3d).

The paper calls problem (8)-(10) "a quadratic convex optimisation problem". :mod:`.hessian`: the
cost (8) is a quadratic in ``vec(R)`` with a constant positive semi-definite Hessian
(:func:`cost_hessian_vec`, :func:`cost_convexity`), and its derivatives on SO(3), computed here
independently of the solvers' own (:func:`cost_derivatives_on_so3`); the constraint set SO(3) is not
convex. :mod:`.starts`: :func:`newton_from_starts` runs Riemannian Newton on SO(3) from given starts
against the certified global minimiser and judges every end point; :func:`nonglobal_summary` counts
the non-global minima, with Wilson intervals, and :func:`nonglobal_view` shows them;
:func:`basin_sensitivity` measures why those counts are brackets (bounds): the basins interleave
finely. :mod:`.minimiser`: :func:`outlier_certificate_study`, the notebook's certificate study under
outlier pairs, and :func:`fixed_point_against_minimiser`, the two-step estimates against the
certified minimiser (notebook 01, section 3d, on fresh problems). :mod:`.claims`:
:func:`convex_problem_record` builds the ledger record from the found and the fresh seeds, its
numbers checked first (:func:`~replication.study.ledger.check_evidence`). :mod:`.counts`:
:func:`count_text` writes a count with its Wilson interval, :func:`bracket_interval` a count as its
bracket.
"""
from .claims import *  # noqa: F403
from .claims import __all__ as _claims_names
from .counts import *  # noqa: F403
from .counts import __all__ as _counts_names
from .hessian import *  # noqa: F403
from .hessian import __all__ as _hessian_names
from .minimiser import *  # noqa: F403
from .minimiser import __all__ as _minimiser_names
from .starts import *  # noqa: F403
from .starts import __all__ as _starts_names

__all__ = [*_counts_names, *_hessian_names, *_starts_names, *_minimiser_names, *_claims_names]
