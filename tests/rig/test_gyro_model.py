"""The numerical core of the gyro's sensor model: the axes' matrix and the misalignment's
Jacobian, the block jackknife and its Student's t critical value."""
import numpy as np
import pytest

from replication.rig import gyro_model as gm
from replication.rig.gyro_model import critical_value
from replication.rig.sensor_model import _pairs, estimate_sensor_model
from replication.rig.streams import GyroStream
from replication.testing import rig_streams


def test_the_axes_matrix_is_the_scale_on_the_diagonal_and_the_terms_symmetric():
    T = gm.axes_matrix(np.log([1.01, 0.99, 1.02]), [0.003, -0.004, 0.005])
    assert np.allclose(np.diag(T), [1.01, 0.99, 1.02]) and np.allclose(T, T.T)
    assert (T[0, 1], T[0, 2], T[1, 2]) == (0.003, -0.004, 0.005)
    assert gm.N_PARAMETERS == 14 and gm.MISALIGNMENT_AXES == ((0, 1), (0, 2), (1, 2))


def test_the_bias_scale_and_misalignment_jacobians_match_finite_differences():
    """With scale and misalignment away from 1 and 0 (the Jacobians use T^-1 exactly, not I)."""
    rng = np.random.default_rng(12)
    R0, camera, gyro, _ = rig_streams(20.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    sigma, mu = np.log([1.03, 0.98, 1.01]), np.array([0.02, -0.015, 0.01])
    raw = GyroStream(gyro.t, gyro.omega @ gm.axes_matrix(sigma, mu).T + [0.03, -0.02, 0.04], "gyro")
    m = estimate_sensor_model(camera, raw)
    i, k = _pairs(camera, raw.t, 1.0, m.offset_mid_s, 0.2)
    i, k = i[::30], k[::30]
    A = np.swapaxes(camera.R[k], -1, -2) @ camera.R[i]
    args = (A, camera.t[i], camera.t[k], 10.0, raw.t, raw.omega)
    s0, m0 = np.log(m.scale), m.misalignment
    r0, jac = gm._linearise(m.R, m.bias_rad_s, m.offset_mid_s, 1e-5, *args, s0, m0)
    assert jac.shape[-1] == 14
    for col in (3, 5, 8, 10, 11, 12, 13):
        step = np.zeros(14)
        step[col] = 1e-6
        moved = gm._linearise(m.R, m.bias_rad_s + step[3:6], m.offset_mid_s, 1e-5, *args, s0 + step[8:11],
                              m0 + step[11:])[0]
        numeric = (moved - r0) / 1e-6
        assert np.abs(numeric - jac[:, :, col]).max() < 0.02 * np.abs(jac[:, :, col]).max() + 1e-9, col
    assert np.abs(jac[:, :, 11:]).max() > 0.1  # the terms move the residuals: a zero column would pass the above


def test_the_held_account_recovers_a_linear_problem_s_truth_and_moves():
    """Residuals linear in the parameters, ``r = J (p - p*)``, at the free ones' optimum with the
    last one held at 0: the joint step reaches ``p*``, and the free ones' optimum moved by ``moves``
    times the held one's change is theirs at the truth."""
    rng = np.random.default_rng(4)
    jac = rng.normal(size=(300, 3, 4))
    truth = np.array([0.3, -0.2, 0.1, 0.05])
    F, h = np.arange(3), np.array([3])
    Jf = jac[:, :, F].reshape(-1, 3)
    free = np.linalg.lstsq(Jf, (jac.reshape(-1, 4) @ truth), rcond=None)[0]  # the free ones' fit, held at 0
    p = np.concatenate([free, [0.0]])
    r = np.einsum("jak,k->ja", jac, p - truth)
    step, cov, moves = gm._held_account(r, jac, np.ones(300), 30, F, h)
    assert np.allclose(p + step, truth) and cov.shape == (4, 4) and moves.shape == (3, 1)
    assert np.allclose(free + moves[:, 0] * (truth[3] - 0.0), truth[:3])


def test_the_critical_value_is_student_s_t_of_the_blocks():
    assert critical_value(7) == pytest.approx(2.447, abs=1e-3)  # 15 s at 20 Hz: 280 pairs, blocks of 40
    assert critical_value(29) == pytest.approx(2.048, abs=1e-3)  # 60 s
    assert critical_value(10 ** 6) == pytest.approx(1.96, abs=1e-3)



def test_the_jackknife_sees_a_block_that_pulls_the_fit():
    """Doubling one block's residuals along a parameter's gradient widens that parameter's jackknife
    deviation."""
    from replication.rig.gyro_model import _block_jackknife

    rng = np.random.default_rng(9)
    jac = rng.normal(size=(400, 3, 2))
    r = rng.normal(size=(400, 3))
    base = _block_jackknife(r, jac, np.ones(400), 40, np.arange(2))
    assert base[1] == 10 and base[0].shape == (2, 2) and np.all(np.linalg.eigvalsh(base[0]) > 0)
    r2 = r.copy()
    r2[:40] *= 5.0
    assert _block_jackknife(r2, jac, np.ones(400), 40, np.arange(2))[0][0, 0] > 2 * base[0][0, 0]
