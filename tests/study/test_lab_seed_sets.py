"""The seed study on its two sets of seeds (``study/lab/seed_sets.py``): the labels the lab's claims
print."""
from test_lab_claims import lab_study

from replication.study.lab.seed_sets import SeedSets


def test_seed_sets_label_both_sets_as_the_checks_name_them():
    s = SeedSets(lab_study(range(1, 21)), lab_study(range(21, 41)))
    assert list(s.sets) == ["seeds 1-20", "fresh seeds 21-40"] and s.n == 20
    assert s.setting.endswith("found on seeds 1-20, confirmed on fresh seeds 21-40 (and the committed draw, seed "
                              "20130501)")
    assert s.both("reversed_loses") == "20 of 20 (84-100 %) on the first and 20 of 20 (84-100 %) on the fresh seeds"
    assert s.deg("single_minus_mean").endswith(" deg on the fresh seeds")
