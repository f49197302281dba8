"""The build's one step beyond pyproject.toml: the project files that installed commands cite,
copied into the wheel.

``fetch-data`` reads ``data/real_data_manifest.csv`` and ``export --help`` cites
``docs/conventions.md``; they live outside the package in the clone, so a wheel carries copies under
``replication/_shipped/`` (same relative paths), where :func:`replication._extras.shipped` finds
them when the clone's are not there. Everything else is declared in pyproject.toml.
"""
import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
#: The project files a wheel ships (the same list as replication._extras.SHIPPED;
#: tests/test_extras.py checks both).
SHIPPED = ("data/real_data_manifest.csv", "docs/conventions.md", "docs/calibration_report.schema.json")


class BuildPyWithShipped(build_py):
    """``build_py``, then the cited project files copied into ``replication/_shipped/``."""

    def run(self):
        super().run()
        for name in SHIPPED:
            target = Path(self.build_lib) / "replication" / "_shipped" / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(ROOT / name, target)


setup(cmdclass={"build_py": BuildPyWithShipped})
