"""The other half of the portability re-runs (see ``test_portability_01_05_06_08.py``): a second
file, so that the second xdist worker takes it."""
import pytest
from test_portability_01_05_06_08 import check_on_another_machine, notebooks


@pytest.mark.portability
@pytest.mark.parametrize("notebook", notebooks(False), ids=lambda p: p.stem)
def test_the_notebook_passes_strict_nbval_on_another_machine(notebook, tmp_path):
    check_on_another_machine(notebook, tmp_path)
