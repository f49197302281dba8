"""Fig. 5 (Sec. III-A): error against sensor noise, the two-step method against SQP (support of
``notebooks/04_noise_sweep.ipynb``).

The paper: with the noise on ``Delta R_i`` rising from 1 to 10 deg (1 deg on ``Delta R_c``), the
two-step error grows "much slower than that of the traditional optimization method": it is "more
resilient to the noise". :mod:`.sweep`: the noise sweep over a grid of settings (which SQP, motions,
start and noise distribution are not stated), its growth ratios with bootstrap intervals, the grid's
rows grouped by problem set, fresh-seed runs and the figure. :mod:`.stop_short`: SQPs that stop
short of the minimum of eq. (8) as the paper's Table I SQP does, matched to it. :mod:`.ranges`: the
growth ratio over motion ranges, and a two-step method that stops short. :mod:`.claims`: the ledger
record of ``fig5_resilience``, from its four pieces of evidence, each checked in the section that
measures it.
"""
from .claims import *  # noqa: F403
from .claims import __all__ as _claims_names
from .ranges import *  # noqa: F403
from .ranges import __all__ as _ranges_names
from .stop_short import *  # noqa: F403
from .stop_short import __all__ as _stop_names
from .sweep import *  # noqa: F403
from .sweep import __all__ as _sweep_names

__all__ = [*_sweep_names, *_stop_names, *_ranges_names, *_claims_names]
