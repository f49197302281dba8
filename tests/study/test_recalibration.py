"""The paper's online re-calibration claim (``replication.study.recalibration``, notebook 02): its
record and checks at their thresholds, and the small-motion study that stops short only with small
motions."""
import pandas as pd
import pytest

from conftest import _valid

# ---- online_recalibration (notebook 02)
# --------------------------------------------------------------------------

def _small(ratio_small=15.0, ratio_large=1.0):
    from replication.study.recalibration import small_motion_study  # noqa: F401 (the frame's producer)

    return pd.DataFrame({"at 50": [45.0, 6.5, 0.42 * ratio_large], "at 50_se": [0.2, 0.3, 0.01],
                         "limit": [45.0 / ratio_small, 1.1, 0.42], "limit_se": [0.1, 0.04, 0.01],
                         "ratio": [ratio_small, 6.5 / 1.1, ratio_large]},
                        index=pd.Index(["0-10 deg", "0-30 deg", "0-90 deg"], name="motions"))


def test_online_recalibration_record_and_its_checks_at_their_thresholds():
    from replication.study.recalibration import online_recalibration_record

    rec = online_recalibration_record(_small(), _small(), section="s", setting="t")
    _valid([rec])
    assert rec["verdict"] == "undecidable from the text"
    assert "motions 0-10 deg: 45.00 ± 0.20 deg at 50 iterations against 3.00 ± 0.10 at its limit" in rec["evidence"]
    assert "With motions 0-10 deg, 0-30 deg the protocol's estimate is several times farther" in rec["evidence"]
    for which in (0, 1):
        for small, large, raises in ((2.001, 1.0, False), (2.0, 1.0, True), (15.0, 1.099, False),
                                     (15.0, 1.1001, True)):
            frames = [_small(), _small()]
            frames[which] = _small(small, large)
            if raises:
                with pytest.raises(ValueError, match="claim 'online_recalibration'.*50 iterations leave"):
                    online_recalibration_record(*frames, section="s", setting="t")
            else:
                assert online_recalibration_record(*frames, section="s", setting="t")["claim"] == \
                    "online_recalibration"


def test_small_motion_study_stops_short_only_with_small_motions():
    from replication.study.recalibration import small_motion_study

    f = small_motion_study(44000, 20, {"0-10 deg": (0.0, 10.0), "0-90 deg": (0.0, 90.0)})
    assert f.loc["0-10 deg", "ratio"] > 5 and abs(f.loc["0-90 deg", "ratio"] - 1) < 0.2
