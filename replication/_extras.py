"""How this project is installed: the optional dependencies (pyproject's extras), the error that
names the extra to install, and the project files an installed copy ships.

The distribution is ``camimu-replication`` (the import name stays ``replication``; ``replication``
on PyPI is an unrelated project, so ``pip install replication`` installs something else). It is
installed from the project's clone, with its lock: ``pip install -c requirements.lock .`` (the core:
the command ``calibrate``, ``export``, the rig API and the solvers), ``pip install -c
requirements.lock '.[study]'`` for the paper's studies, ``reproduce``, ``claims``, ``generate-lab``
and ``calibrate --online``; ``bash scripts/setup.sh`` installs everything, editable. An optional
package is imported where it is used, through :func:`require`, so a missing one is an
``ImportError`` that says which extra brings it and how to install it from the clone, not a bare
``No module named ...``.
"""
from __future__ import annotations

import importlib
from pathlib import Path

__all__ = ["DISTRIBUTION", "OPTIONAL", "SHIPPED", "MissingExtra", "require", "missing_message", "shipped"]

#: The distribution's name (pyproject.toml; free on PyPI: ``pip index versions camimu-replication``
#: finds nothing).
DISTRIBUTION = "camimu-replication"

#: The project files that commands cite, copied into a wheel under ``replication/_shipped/``
#: (setup.py).
SHIPPED = ("data/real_data_manifest.csv", "docs/conventions.md", "docs/calibration_report.schema.json")

#: Optional top-level module -> the extra of pyproject.toml that installs it (tests/test_extras.py
#: checks both).
OPTIONAL = {"pandas": "study", "tabulate": "study", "tqdm": "study", "nbclient": "study", "nbformat": "study",
            "ipykernel": "study", "ahrs": "study", "jupyter": "notebooks"}


class MissingExtra(ImportError):
    """An optional package is not installed; the message names the extra that installs it and what
    needed it."""


def missing_message(module: str, purpose: str) -> str:
    """The sentence for an optional ``module`` that is not installed, needed for ``purpose``.

    >>> print(missing_message("pandas", "calibrate --online")[:80])
    calibrate --online needs pandas, which is not installed: in the project's clone,
    >>> message = missing_message("pandas", "calibrate --online")
    >>> "pip install -c requirements.lock '.[study]'" in message
    True
    """
    extra = OPTIONAL.get(module.split(".")[0], "study")
    return (f"{purpose} needs {module}, which is not installed: in the project's clone, pip install -c "
            f"requirements.lock '.[{extra}]' (or bash scripts/setup.sh for everything; not pip install "
            f"'replication[{extra}]': replication on PyPI is an unrelated project)")


def shipped(relative: str) -> Path:
    """The project file ``relative`` (``data/...``, ``docs/...``, one of :data:`SHIPPED`): the
    clone's, or the copy an installed wheel carries in ``replication/_shipped/``."""
    package = Path(__file__).resolve().parent
    clone = package.parent / relative
    return clone if clone.exists() else package / "_shipped" / relative


def require(module: str, purpose: str):
    """Import an optional ``module`` for ``purpose`` (e.g. ``"replication.rig.live.replay"``).

    Raises
    ------
    MissingExtra
        An ``ImportError``: the module is not installed; the message names the extra that installs
        it (:func:`missing_message`) and ``name`` is the module's.
    """
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise MissingExtra(missing_message(module, purpose), name=module) from err
