"""Fig. 5's claim in pieces (``study/fig5/claims.py``): each piece of evidence checks its own
numbers."""
import pytest
from test_fig5 import FAIL, _record_inputs

from replication.study.fig5 import claims as fig5_claims


@pytest.mark.parametrize("failing_share, settings", [(0.87, "(2 settings)"), (0.8701, "(1 settings)")])
def test_far_start_counts_a_row_as_failing_from_its_share_on(failing_share, settings):
    inp = _record_inputs()   # the far-start rows fail in 87 % and in all of their runs
    stop_keys = list(inp["stop_levels"].index.droplevel(-1).unique())
    growth = inp["found"].drop(index=stop_keys)
    far = fig5_claims.far_start(growth, inp["fresh"], n_runs=150, failing_share=failing_share)
    assert settings in far["text"]


def test_far_start_names_the_fresh_settings_it_was_confirmed_on():
    inp = _record_inputs()
    stop_keys = list(inp["stop_levels"].index.droplevel(-1).unique())
    growth = inp["found"].drop(index=stop_keys)
    assert fig5_claims.far_start(growth, inp["fresh"], n_runs=150)["fresh_settings"] == 1
    assert fig5_claims.far_start(growth, inp["fresh"].drop(index=FAIL[0]), n_runs=150)["fresh_settings"] == 0
