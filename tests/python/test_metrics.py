"""sflsh.metrics, read_dyna and write_dyna: a DYNA file round trip, the metric on registrations without dynamics
(pure skinning: σ ≈ 0) and on a simulation's surface (σ as the simulator measures it), and errors."""
import numpy as np
import pytest

import sflsh


@pytest.fixture(scope="module")
def body():
    return sflsh.Body()


def test_dyna_round_trip(body, scratch):
    scratch.mkdir(parents=True, exist_ok=True)
    m = sflsh.Motion("shake_hips", frames=3)
    posed = body.pose(sflsh.subject("OPEN_TRAIN_1"), m.poses, m.trans)
    path = scratch / "dyna.h5"
    sflsh.write_dyna(str(path), body.faces, {"OPEN_TRAIN_1_shake_hips": posed}, fps=60.0)
    data = sflsh.read_dyna(str(path))
    np.testing.assert_array_equal(data["faces"], body.faces)
    np.testing.assert_array_equal(data["sequences"]["OPEN_TRAIN_1_shake_hips"], posed)   # float64 both ways
    assert data["fps"]["OPEN_TRAIN_1_shake_hips"] == 60.0
    # The file is in DYNA's own layout, as h5py (how DYNA is read in Python) sees it: one (V, 3, T) dataset per key.
    import h5py
    with h5py.File(path, "r") as f:
        assert f["OPEN_TRAIN_1_shake_hips"].shape == (body.num_vertices, 3, 3)
        np.testing.assert_array_equal(np.moveaxis(f["OPEN_TRAIN_1_shake_hips"][...], 2, 0), posed)
        np.testing.assert_array_equal(f["faces"][...], body.faces)
    with pytest.raises(sflsh.Error, match="nope"):
        sflsh.read_dyna(str(path), key="nope")


def test_metric_of_pure_skinning_is_zero(body):
    # Registrations that are exactly the skinned body carry no soft-tissue dynamics: the fitted pose reproduces
    # them and σ is the fit's residual, far below a millimetre (simulated σ is millimetres).
    m = sflsh.Motion("shake_hips", frames=3)
    beta = sflsh.subject("OPEN_TRAIN_1")
    posed = body.pose(beta, m.poses, m.trans)
    result = sflsh.metrics(posed, body.faces, beta)
    assert result["sigma"].shape == (body.num_vertices,) and result["sigma"].dtype == np.float64
    assert result["poses"].shape == (3, 72) and not result["beta_fitted"]
    assert result["sigma"].max() < 1e-4


def test_metric_errors(body):
    with pytest.raises(sflsh.Error, match="vertices"):
        sflsh.metrics(np.zeros((3, 10, 3)))
    with pytest.raises(sflsh.Error, match="at least 2"):
        sflsh.metrics(body.pose(None, np.zeros((1, 72))))
    with pytest.raises(sflsh.Error, match="faces"):
        sflsh.metrics(body.pose(None, np.zeros((2, 72))), body.faces[:10])
