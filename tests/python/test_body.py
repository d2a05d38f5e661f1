"""sflsh.Body, subjects and motions: shapes and dtypes, views without copies, errors, and posing equal to
`sflsh motion export`."""
import numpy as np
import pytest

import sflsh
from conftest import read_vtp, run_cli


@pytest.fixture(scope="module")
def body():
    return sflsh.Body()


def test_arrays_have_the_smpl_shapes_and_dtypes(body):
    n = body.num_vertices
    assert n == 6929 and body.num_faces == 13854   # the open body (README, "The open body in numbers")
    assert body.v_template.shape == (n, 3) and body.v_template.dtype == np.float64
    assert body.faces.shape == (body.num_faces, 3) and body.faces.dtype == np.int32
    assert body.weights.shape == (n, 24) and body.weights.dtype == np.float64
    assert body.shapedirs.shape[:2] == (n, 3) and body.shapedirs.shape[2] >= 10
    assert body.joint_regressor.shape == (24, n)
    assert len(body.parents) == 24 and body.parents[0] == -1 and len(sflsh.Body.joint_names) == 24
    assert body.shape(None).shape == (n, 3) and body.joints(None).shape == (24, 3)


def test_views_share_the_bodys_memory_and_are_read_only(body):
    # Two calls of a view accessor see the same buffer, owned by the Body (no copy per call).
    for name in ("v_template", "faces", "weights", "shapedirs"):
        a, b = getattr(body, name), getattr(body, name)
        assert np.shares_memory(a, b), name
        assert a.base is not None and not a.flags.writeable, name
    with pytest.raises(ValueError):
        body.v_template[0, 0] = 1.0
    # shapedirs[v, c, k] is column k of the (3n) × B matrix at row 3v + c (SMPL's n × 3 × B layout).
    beta = np.zeros(10)
    beta[0] = 1.0
    np.testing.assert_allclose(body.shape(beta) - body.v_template, body.shapedirs[:, :, 0], rtol=0, atol=1e-15)


def test_results_own_their_memory(body):
    v = body.shape(np.ones(10))
    assert v.flags.writeable and v.flags.c_contiguous
    assert not np.shares_memory(v, body.shape(np.ones(10)))


def test_subjects_and_motions():
    subjects = sflsh.subjects()
    assert "OPEN_TRAIN_1" in subjects and "DYNA_1" in subjects
    np.testing.assert_array_equal(sflsh.subject("OPEN_TEST_3"), subjects["OPEN_TEST_3"])
    assert subjects["OPEN_TRAIN_1"].shape == (10,)
    assert set(sflsh.motions()) >= {"one_leg_jump", "running_on_spot", "shake_hips", "jiggle_on_toes", "shake_shoulders", "dance"}
    m = sflsh.Motion("jiggle_on_toes", fps=30, frames=12)
    assert m.num_frames == 12 and m.fps == 30
    assert m.poses.shape == (12, 72) and m.trans.shape == (12, 3) and m.world_from_body.shape == (3, 3)
    assert np.shares_memory(m.poses, m.poses) and not m.poses.flags.writeable
    np.testing.assert_allclose(m.times, np.arange(12) / 30.0, rtol=0, atol=1e-15)


def test_pose_is_vectorized_over_frames(body):
    m = sflsh.Motion("shake_hips", frames=4)
    beta = sflsh.subject("OPEN_TRAIN_2")
    all_frames = body.pose(beta, m.poses, m.trans)
    assert all_frames.shape == (4, body.num_vertices, 3)
    np.testing.assert_array_equal(all_frames[2], body.pose(beta, m.poses[2], m.trans[2]))
    assert body.pose_joints(beta, m.poses, m.trans).shape == (4, 24, 3)


def test_errors_are_exceptions_with_the_clis_messages(body, scratch):
    with pytest.raises(sflsh.Error, match="missing.npz"):
        sflsh.Body(str(scratch / "missing.npz"))
    with pytest.raises(sflsh.Error, match="NOBODY"):
        sflsh.subject("NOBODY")
    with pytest.raises(sflsh.Error, match="72"):
        body.pose(None, np.zeros(71))
    with pytest.raises(sflsh.Error, match="betas"):
        body.shape(np.zeros(11))
    with pytest.raises(sflsh.Error, match="no_such_motion"):
        sflsh.Motion("no_such_motion")
    assert issubclass(sflsh.Error, RuntimeError)


def test_posed_vertices_equal_motion_export(body, cli, scratch):
    # The CLI and the module pose with the same code (body::Poser, then world_from_body); the .vtp points are
    # Float64, so the only difference allowed is none at all beyond round-off: 1e-12 m.
    out = scratch / "export"
    frames = 5
    r = run_cli(cli, "motion", "export", "--subject", "OPEN_TRAIN_1", "--motion", "one_leg_jump", "--frames", str(frames),
                "--out", str(out))
    assert r.returncode == 0, r.stderr
    m = sflsh.Motion("one_leg_jump", frames=frames)
    posed = body.pose(sflsh.subject("OPEN_TRAIN_1"), m.poses, m.trans, world_from_body=m.world_from_body)
    for t in range(frames):
        points, fields = read_vtp(out / f"body_{t:06d}.vtp")
        np.testing.assert_allclose(posed[t], points, rtol=0, atol=1e-12)


def test_amass_motion_round_trip(scratch):
    # Motion.save writes AMASS's .npz layout; Motion(path) reads it back frame for frame at the file's rate.
    scratch.mkdir(parents=True, exist_ok=True)
    m = sflsh.Motion("dance", fps=30, frames=8)
    path = scratch / "dance.npz"
    m.save(str(path))
    back = sflsh.Motion(str(path), fps=30)
    assert back.source == str(path) and back.num_frames == 8
    np.testing.assert_allclose(back.poses, m.poses, rtol=0, atol=1e-12)
    np.testing.assert_allclose(back.trans, m.trans, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(back.world_from_body, m.world_from_body)
