"""The optional dependencies (pyproject's extras) and the error that names the extra to install.

The core install (``pip install replication``) calibrates a rig: the command ``calibrate``, the rig API and the
solvers. The paper's studies, ``reproduce``, ``claims``, ``generate-lab`` and ``calibrate --online`` need the extra
``study`` (``pip install 'replication[study]'``; ``bash scripts/setup.sh`` installs everything). An optional package
is imported where it is used, through :func:`require`, so a missing one is an ``ImportError`` that says which extra
brings it, not a bare ``No module named ...``.
"""
from __future__ import annotations

import importlib

__all__ = ["OPTIONAL", "MissingExtra", "require", "missing_message"]

#: Optional top-level module -> the extra of pyproject.toml that installs it (tests/test_install.py checks both).
OPTIONAL = {"pandas": "study", "tabulate": "study", "tqdm": "study", "nbclient": "study", "nbformat": "study",
            "ipykernel": "study", "ahrs": "study", "jupyter": "notebooks"}


class MissingExtra(ImportError):
    """An optional package is not installed; the message names the extra that installs it and what needed it."""


def missing_message(module: str, purpose: str) -> str:
    """The sentence for an optional ``module`` that is not installed, needed for ``purpose``.

    >>> print(missing_message("pandas", "calibrate --online")[:89])
    calibrate --online needs pandas, which is not installed: pip install 'replication[study]'
    """
    extra = OPTIONAL.get(module.split(".")[0], "study")
    return (f"{purpose} needs {module}, which is not installed: pip install 'replication[{extra}]' "
            "(or bash scripts/setup.sh for everything)")


def require(module: str, purpose: str):
    """Import an optional ``module`` for ``purpose`` (e.g. ``"replication.rig.live.replay"``).

    Raises
    ------
    MissingExtra
        An ``ImportError``: the module is not installed; the message names the extra that installs it
        (:func:`missing_message`) and ``name`` is the module's.
    """
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise MissingExtra(missing_message(module, purpose), name=module) from err
