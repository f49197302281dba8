"""Notebook 05's synthetic seed studies for the tests of the lab's studies and claims
(``tests/study/test_lab_study.py``, ``test_lab_claims.py``): a :func:`seed_study` frame whose
findings pass every check of the lab's claims, each with a set margin, and a pitch-bias
intervention frame with a set mean and interval."""
import numpy as np
import pandas as pd

#: SQP's runs in the seed study (the columns ``failed_sqp_<run>``).
SQP_RUNS = ["100 iterations", "1000 iterations", "cost (8) / 2J"]
#: The column suffixes of the interventions: the magnetometer's noise, its calibration errors
#: off.
NOISE, CAL = "_without_magnetometer_noise", "_without_magnetometer_calibration_errors"


def lab_study(seeds):
    """A synthetic :func:`seed_study` frame whose findings pass every check of the lab's claims,
    each with a margin the threshold tests of test_lab_claims.py compute."""
    seeds = pd.Index(list(seeds), name="seed")
    n = len(seeds)
    r, alt = np.linspace(0.0, 1.0, n), np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    rms_true = 1.2 + 0.2 * r
    shared = 1.8 + 0.5 * r
    frame = {
        "rms_true_R0": rms_true, "rms_ours_right": rms_true - 0.01 + 0.01 * alt,
        "rms_reversed_ours_right": rms_true + 0.2 + 0.1 * alt, "rms_turned_2": rms_true + 0.2 + 0.02 * alt,
        "rms_turned_5": rms_true + 0.5, "rms_turned_10": rms_true + 1.4, "rms_sensor_frame": 24.0 + r,
        "shared_bias_ours_right": shared, "spread_ours_right": np.full(n, 1.5),
        "pitch_bias_true_R0": -(1.8 + 0.4 * r),
        "true_ours_right": 2.3 + 0.2 * r, "corr_roll_ours_right": 0.998 + 0.0005 * r,
        "corr_pitch_ours_right": 0.993 + 0.005 * r, "corr_yaw_ours_right": 0.9995 + 0.0004 * r,
        "failed_sqp_100 iterations": np.where(np.arange(n) < n - 2, 2, 0),
        "failed_sqp_1000 iterations": np.where(np.arange(n) < 8, 1, 0), "failed_sqp_cost (8) / 2J": np.zeros(n),
    }
    frame["true_all_ours_right"] = frame["true_ours_right"] - 0.002 + 0.001 * alt
    frame["true_single_ours_right"] = frame["true_ours_right"] + 0.35 + 0.1 * alt
    frame["limit_sqp_100 iterations"] = frame["failed_sqp_100 iterations"]
    frame["corr_ours_right"] = np.minimum.reduce([frame[f"corr_{a}_ours_right"] for a in ("roll", "pitch", "yaw")])
    for tag, shared_off, pitch_off in ((NOISE, shared + 0.004 * alt, 0.4 + 0.1 * r),
                                       (CAL, 0.65 + 0.1 * r, 1.8 + 0.4 * r + 0.05 * alt)):
        frame["shared_bias_ours_right" + tag], frame["pitch_bias_true_R0" + tag] = shared_off, pitch_off
        frame["rms_ours_right" + tag], frame["rms_true_R0" + tag] = rms_true, rms_true + 0.01
        frame["true_ours_right" + tag] = frame["true_ours_right"]
    return pd.DataFrame(frame, index=seeds)



def pitch_frame(seeds, mean=0.02, half_width=0.06, base=1.9):
    """A synthetic :func:`replication.study.lab.pitch_bias_intervention` frame: the change of |pitch
    bias| alternates about ``mean`` so that its 95 % half-width (1.96 SE) is ``half_width``."""
    seeds = pd.Index(list(seeds), name="seed")
    n = len(seeds)
    alt = np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    sd = half_width / 1.96 * np.sqrt(n)
    change = mean + alt * sd * np.sqrt((n - 1) / n)   # sample SD (ddof=1) exactly sd
    return pd.DataFrame({"pitch_bias": -np.full(n, base), "pitch_bias_without": -(base + change)}, index=seeds)
