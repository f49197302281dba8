"""The lab's seed study on the two sets of seeds its claims rest on, in the words the ledger uses:
the seeds where each finding was made (1-20 in notebook 05) and the fresh ones where it was checked
again (21-40), each with its :func:`~replication.study.lab.seed_findings`, and the setting each
record of the lab names. The claims themselves are in :mod:`replication.study.lab.claims`.
"""
from __future__ import annotations

import pandas as pd

from .study import seed_findings, seed_range, seed_spread

__all__ = ["LAB_SETTING", "SeedSets", "check_disjoint", "found_setting"]

#: The setting of every record of the lab.
LAB_SETTING = "simulated lab (LabSettings defaults: datasheet noise, residual calibration errors as documented)"
_COMMITTED = "(and the committed draw, seed 20130501)"


def check_disjoint(found, fresh, what: str) -> None:
    """``ValueError`` naming the shared seeds unless the ``fresh`` seeds are disjoint from the
    ``found`` ones: a finding is confirmed only on seeds it was not made on."""
    shared = sorted(set(found) & set(fresh))
    if shared:
        shown = ", ".join(str(int(s)) for s in shared[:5]) + (" ..." if len(shared) > 5 else "")
        raise ValueError(f"{what}: the fresh seeds repeat {len(shared)} of the seeds the findings were made on "
                         f"({shown}); a finding is confirmed only on seeds disjoint from those")


def found_setting(study: pd.DataFrame) -> str:
    """The setting of a claim measured on the seeds where the findings were made (and the committed
    draw)."""
    return f"{LAB_SETTING}; {seed_range(study)} {_COMMITTED}"


class SeedSets:
    """Two :func:`~replication.study.lab.seed_study` frames side by side: ``study`` (the seeds where
    the findings were made) and ``fresh`` (where each is checked again), their findings ``found``
    and ``confirmed``, and ``sets``: ``{label: (frame, findings)}``, labelled as the checks name
    them (``"seeds 1-20"``, ``"fresh seeds 21-40"``)."""

    def __init__(self, study: pd.DataFrame, fresh: pd.DataFrame):
        check_disjoint(study.index, fresh.index, "the seed study")
        self.study, self.fresh = study, fresh
        self.found, self.confirmed = seed_findings(study), seed_findings(fresh)
        found_seeds, fresh_seeds = seed_range(study), seed_range(fresh)
        self.sets = {found_seeds: (study, self.found), "fresh " + fresh_seeds: (fresh, self.confirmed)}
        self.n = len(study)
        #: The setting of a claim found on the first seeds and confirmed on the fresh ones.
        self.setting = f"{LAB_SETTING}; found on {found_seeds}, confirmed on fresh {fresh_seeds} {_COMMITTED}"

    def both(self, key: str, unit: str = "") -> str:
        """``"<found><unit> on the first and <fresh><unit> on the fresh seeds"``: one finding's text
        on both sets."""
        return f"{self.found.loc[key, 'text']}{unit} on the first and {self.confirmed.loc[key, 'text']}{unit} on the " \
               "fresh seeds"

    def deg(self, key: str) -> str:
        """:meth:`both` in degrees."""
        return self.both(key, " deg")

    def spread(self, which: str, column: str, digits: int = 2) -> str:
        """:func:`~replication.study.lab.seed_spread` of ``column`` of ``"study"`` or
        ``"fresh"``."""
        return seed_spread(getattr(self, which)[column], digits)
