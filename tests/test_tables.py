import numpy as np
import pandas as pd
import pytest

from replication import paper
from replication.simulation import simulate
from replication.tables import iterate_errors, table1, versus_paper


def test_iterate_errors_shapes_and_noise_free_convergence():
    sim = simulate(2, 4, noise_camera=0.0, noise_sensor=0.0)
    errs = iterate_errors(sim, iterations=30)
    assert set(errs) == {"optimization", "ours_right", "ours_left"}
    assert all(e.shape == (4, 30) for e in errs.values())
    assert errs["ours_right"][:, -1].max() < 1e-9 and errs["optimization"][:, -1].max() < 1e-6
    assert set(iterate_errors(sim, iterations=30, with_sqp=False)) == {"ours_right", "ours_left"}


def test_table1_picks_the_right_iterations():
    err = np.tile(np.arange(1.0, 51.0), (3, 1))  # error = iteration number, identical runs
    tab = table1({"ours_right": err})
    assert list(tab.index) == list(paper.TABLE1_ITERATIONS)
    assert np.array_equal(tab[("ours_right", "mean")], paper.TABLE1_ITERATIONS)
    assert np.all(tab[("ours_right", "std")] == 0)


def test_versus_paper_verdicts():
    ref = paper.load_table1()
    cols = {}
    for m in paper.TABLE1_METHODS:
        means = ref.xs(m, level="method")["mean"].to_numpy()
        cols[(m, "mean")], cols[(m, "std")] = means.copy(), np.zeros_like(means)
    ours = pd.DataFrame(cols, index=pd.Index(paper.TABLE1_ITERATIONS, name="iteration"))
    assert (versus_paper(ours)["verdict"] == "agrees").all()
    ours.loc[2, ("ours_right", "mean")] *= 1.3  # 30 % off: beyond the 25 % tolerance
    ours.loc[50, ("ours_left", "mean")] += 0.004  # within the 0.005 absolute floor
    cmp = versus_paper(ours)
    assert cmp.loc[(2, "ours_right"), "verdict"] == "differs"
    assert cmp.loc[(50, "ours_left"), "verdict"] == "agrees"
    assert cmp.loc[(2, "ours_right"), "difference"] == pytest.approx(0.3 * 2.339, abs=1e-3)
