"""The held gyro terms' effect on R0 and the triangular T_g's frame (replication.rig.gyro_held)."""
import dataclasses
import math

import numpy as np
import pytest
from scipy.linalg import polar

from replication.core.so3 import angle_between_deg
from replication.rig import sensor_model as sm
from replication.rig.calibration import calibrate
from replication.rig.gyro_held import (
    HELD_PRIORS,
    HELD_R0_BOUND_DEG,
    held_effect_deg,
    held_lines,
    held_reasons,
    held_report,
    triangular_frame_deg,
)
from replication.rig.gyro_model import axes_matrix
from replication.rig.streams import GyroStream
from replication.testing import misaligned_rig, rig_streams


def _coupled(couplings):
    """A 14 x 14 normal matrix, identity but for R0's x row coupled to the given parameters."""
    H = np.eye(14)
    for j, c in couplings.items():
        H[0, j] = H[j, 0] = c
    return H


def test_a_held_term_moves_r0_by_its_coupling_times_its_prior():
    free, c = np.arange(13), 0.3
    deg, per = held_effect_deg(_coupled({13: c}), free, [13], [0.02])
    assert deg == pytest.approx(math.degrees(c * 0.02)) and per == pytest.approx([deg])


def test_held_terms_combine_with_their_worst_signs():
    free = np.arange(12)
    deg, per = held_effect_deg(_coupled({12: 0.3, 13: -0.2}), free, [12, 13], [0.02, 0.03])
    assert deg == pytest.approx(math.degrees(0.3 * 0.02 + 0.2 * 0.03))
    assert per == pytest.approx(np.degrees([0.006, 0.006]))


def test_a_free_parameter_that_absorbs_the_held_one_leaves_r0_unmoved():
    rng = np.random.default_rng(0)
    J = rng.normal(size=(200, 14))
    J[:, 13] = J[:, 9]  # the held term's Jacobian is a free one's: the re-fit takes it all
    deg, _ = held_effect_deg(J.T @ J, np.arange(13), [13], [0.02])
    assert deg < 1e-9
    alone, _ = held_effect_deg(J.T @ J, np.setdiff1d(np.arange(13), [9]), [13], [0.02])
    assert alone > 1e-3  # without that free parameter the held term moves R0


def test_no_held_terms_move_nothing_and_bad_inputs_are_refused():
    assert held_effect_deg(np.eye(14), np.arange(14), [], [])[0] == 0.0
    with pytest.raises(ValueError, match="must include R0's rotation"):
        held_effect_deg(np.eye(14), np.arange(3, 13), [13], [0.02])
    with pytest.raises(ValueError, match="non-negative"):
        held_effect_deg(np.eye(14), np.arange(13), [13], [-0.02])
    with pytest.raises(ValueError, match="finite"):
        held_effect_deg(np.full((14, 14), np.nan), np.arange(13), [13], [0.02])


@pytest.mark.parametrize("m", [0.0074, 0.03])
@pytest.mark.parametrize("which", ["upper", "lower"])
def test_the_triangular_frame_is_the_polar_rotation_of_a_triangular_t_g(m, which):
    T = np.diag([1.01, 0.99, 1.02])
    idx = np.triu_indices(3, 1) if which == "upper" else np.tril_indices(3, -1)
    T[idx] = m
    U, P = polar(T, side="left")  # T = P U: the gyro reads P (U omega), U turns the triangular frame to R0's
    mu = [P[0, 1], P[0, 2], P[1, 2]]
    got = triangular_frame_deg(np.diag(P), mu)
    assert got[which] == pytest.approx(angle_between_deg(U, np.eye(3)), abs=1e-9)
    assert got[which] == pytest.approx(math.degrees(np.linalg.norm(mu)), rel=0.02)  # first order: |mu|
    assert triangular_frame_deg(np.ones(3), np.zeros(3)) == {"upper": 0.0, "lower": 0.0}
    with pytest.raises(ValueError, match="positive determinant"):
        triangular_frame_deg([1.0, 1.0, 1.0], [1.0, 1.0, 1.0])


@pytest.fixture(scope="module")
def model():
    rng = np.random.default_rng(3)
    _, camera, gyro, _ = rig_streams(30.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    return sm.estimate_sensor_model(camera, gyro)


def _one_held(model, effect_deg):
    """``model`` with the misalignment yz held and coupled to R0 so that it moves R0 by
    ``effect_deg`` at its prior."""
    c = math.radians(effect_deg) / HELD_PRIORS["misalignment"]
    return dataclasses.replace(model, normal_matrix=_coupled({13: c}), scale_resolved=np.ones(3, bool),
                               misalignment_resolved=np.array([True, True, False]), misalignment=np.zeros(3),
                               scale=np.ones(3), scale_note=None)


@pytest.mark.parametrize("factor, fires", [(0.99, False), (1.01, True)])
def test_the_held_reason_at_its_bound(model, factor, fires):
    moved = _one_held(model, factor * HELD_R0_BOUND_DEG)
    assert held_report(moved)["held_R0_deg"] == pytest.approx(factor * HELD_R0_BOUND_DEG)
    found = [x for x in held_reasons(moved) if x.check == "gyro_held"]
    assert bool(found) == fires
    if fires:
        (reason,) = found
        assert reason.level == "warning" and reason.threshold == HELD_R0_BOUND_DEG
        assert "misalignment yz" in reason.message and "could move R0 by up to 0.35 deg" in reason.message
        assert "+-2 %" in reason.message


def test_a_model_that_held_everything_for_its_units_names_no_held_terms(model):
    moved = dataclasses.replace(_one_held(model, 5.0), scale_note="a scale of [57.3, ...] fitted")
    assert held_report(moved)["held_terms"] == [] and not held_reasons(moved)


@pytest.mark.parametrize("factor, resolved, fires", [(0.99, True, False), (1.01, True, True), (1.01, False, False)])
def test_the_triangular_frame_reason_at_its_bound(model, factor, resolved, fires):
    m = math.radians(factor * HELD_R0_BOUND_DEG) / math.sqrt(3.0)  # three equal terms: |mu| the angle
    moved = dataclasses.replace(model, misalignment=np.full(3, m), misalignment_resolved=np.full(3, resolved),
                                scale=np.ones(3), scale_resolved=np.ones(3, bool))
    tri = held_report(moved)["triangular_frame_deg"]
    assert max(tri.values()) == pytest.approx(factor * HELD_R0_BOUND_DEG, rel=2e-3)
    found = [x for x in held_reasons(moved) if x.check == "gyro_triangular_frame"]
    assert bool(found) == fires
    if fires:
        assert "R0 refers to the gyro's orthogonalised frame" in found[0].message
        assert "triangular T_g" in found[0].message


def test_the_summary_lines_name_the_frame_and_the_held_terms(model):
    lines = held_lines(held_report(_one_held(model, 0.5)))
    assert lines[0].startswith("R0's sensor frame: the gyro's orthogonalised frame")
    assert "misalignment yz" in lines[1] and "up to 0.5 deg" in lines[1]
    assert held_lines({}) == []  # a report without the fields


def test_a_short_recording_with_misaligned_axes_is_not_ok():
    """10 s of three-axis motion, 1.5 % terms: all held, R0 1.3 deg off (the terms held at 0)."""
    R0, camera, gyro, _ = misaligned_rig(71001, 0.0, seconds=10.0)
    T = axes_matrix(np.zeros(3), [0.015] * 3)
    bias = np.array([0.03, -0.02, 0.04])  # misaligned_rig's
    gyro = GyroStream(gyro.t, (gyro.omega - bias) @ T.T + bias, "gyro")
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    report = r.to_dict()["sensor_model"]
    assert "misalignment xy" in report["held_terms"]
    assert r.verdict.level != "ok"
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_held"]
    assert reason.measured > HELD_R0_BOUND_DEG
    assert any(line.startswith("gyro terms held (not resolved)") for line in r.summary().splitlines())


def test_a_triangular_t_g_is_named_with_the_angle_r0_is_off_the_body_frame():
    """40 s, an upper triangular T_g with 0.74 % terms: half of each a symmetric 0.37 % (under the
    misalignment reason's bound), half a rotation R0 takes up; it was ``ok`` with nothing said."""
    R0, camera, gyro, _ = misaligned_rig(63000, 0.0)
    T = np.eye(3)
    T[np.triu_indices(3, 1)] = 0.0074
    bias = np.array([0.03, -0.02, 0.04])
    r = calibrate(camera, GyroStream(gyro.t, (gyro.omega - bias) @ T.T + bias, "gyro"), n_bootstrap=0,
                  diagnose=False)
    tri = r.to_dict()["sensor_model"]["triangular_frame_deg"]["upper"]
    assert tri == pytest.approx(angle_between_deg(r.R, R0), abs=0.03)  # R0 differs from the body frame by it
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_triangular_frame"]
    assert r.verdict.level == "warning" and reason.measured > HELD_R0_BOUND_DEG
    assert any(line.startswith("R0's sensor frame") for line in r.summary().splitlines())


def test_the_misalignment_reason_states_the_triangular_frame_s_angle():
    """One 1 % term of a triangular T_g: the misalignment reason said R0 moves by about 0.05 deg
    while R0 is 0.29 deg from the body frame; it now states that angle."""
    R0, camera, gyro, _ = misaligned_rig(63002, 0.0)
    T = np.eye(3)
    T[0, 1] = 0.01
    bias = np.array([0.03, -0.02, 0.04])
    r = calibrate(camera, GyroStream(gyro.t, (gyro.omega - bias) @ T.T + bias, "gyro"), n_bootstrap=0,
                  diagnose=False)
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_misalignment"]
    words = reason.message.split("R0 refers to the gyro's orthogonalised frame, ")[1]
    angle = float(words.split(" deg from the frame of a triangular T_g")[0])
    assert angle == pytest.approx(angle_between_deg(r.R, R0), abs=0.03) and angle < HELD_R0_BOUND_DEG
    assert not [x for x in r.verdict.reasons if x.check == "gyro_triangular_frame"]  # under the floor
