"""sflsh.Simulation: reduced and full-space runs equal to `sflsh simulate` for the same inputs, arrays without copies, errors as
exceptions, and Ctrl-C (KeyboardInterrupt) at a frame boundary leaving the simulation usable.

The runs are short (coarse layer, a few frames) so the whole file stays within seconds once the reduced model is
in the test cache.
"""
import json
import threading
import _thread

import numpy as np
import pytest

import sflsh
from conftest import read_vtp, run_cli

FRAMES = 6
SETTINGS = dict(subject="OPEN_TRAIN_1", motion="jiggle_on_toes", frames=FRAMES, solver="reduced", mesh="coarse")


@pytest.fixture()
def simulation(cache):
    return sflsh.Simulation(**SETTINGS, cache=cache)


def test_reduced_run_equals_the_cli(cli, cache, scratch):
    out = scratch / "run"
    r = run_cli(cli, "simulate", "--solver", "reduced", "--mesh", "coarse", "--subject", "OPEN_TRAIN_1", "--motion",
                "jiggle_on_toes", "--frames", str(FRAMES), "--format", "vtk", "--cache", cache, "--out", str(out))
    assert r.returncode == 0, r.stderr
    sim = sflsh.Simulation(**SETTINGS, cache=cache)
    result = sim.run()
    n = sim.num_vertices
    assert result["vertices"].shape == (FRAMES, n, 3) and result["vertices"].dtype == np.float64
    assert result["soft_tissue_displacement"].shape == (FRAMES, n, 3)
    np.testing.assert_array_equal(result["frames"], np.arange(FRAMES))
    # Same code path (scene::BodySimulation) on the same inputs; 1e-9 m leaves room for the threaded sums of the
    # cubature (TBB) only: the runs agree to round-off.
    for t in range(FRAMES):
        points, fields = read_vtp(out / f"body_{t:06d}.vtp")
        np.testing.assert_allclose(result["vertices"][t], points, rtol=0, atol=1e-9)
        np.testing.assert_allclose(result["soft_tissue_displacement"][t], fields["soft_tissue_displacement"], rtol=0, atol=1e-9)
    assert np.abs(result["soft_tissue_displacement"][-1]).max() > 1e-5   # there is soft-tissue motion to compare
    _, dynamics = read_vtp(out / "dynamics.vtp")
    sigma, sigma_n, sigma_t = sim.sigma()
    for mine, name in ((sigma, "sigma"), (sigma_n, "sigma_normal"), (sigma_t, "sigma_tangent")):
        np.testing.assert_allclose(1e3 * mine, dynamics[name], rtol=0, atol=1e-6)   # mm in dynamics.vtp
    summary = sim.summary()
    cli_summary = json.loads((out / "summary.json").read_text())
    for key in ("solver", "integrator", "mass", "subject", "beta", "motion", "mesh", "material"):
        assert summary[key] == cli_summary[key], key
    assert [f["newton_iterations"] for f in summary["frames"]] == [f["newton_iterations"] for f in cli_summary["frames"]]
    assert summary["dynamics"]["sigma_mean_mm"] == pytest.approx(cli_summary["dynamics"]["sigma_mean_mm"], rel=1e-9)
    assert summary["reduced"]["coordinates"] == cli_summary["reduced"]["coordinates"]


def test_full_space_run_equals_the_cli(cli, cache, scratch):
    # The full-space solver in the module's process (PETSc and MPI started on first use, one process) against
    # `sflsh simulate --solver full`: the same solves on the same inputs, so again equal to round-off (1e-9 m).
    out = scratch / "run"
    r = run_cli(cli, "simulate", "--solver", "full", "--mesh", "coarse", "--subject", "OPEN_TRAIN_2", "--motion",
                "shake_hips", "--frames", "3", "--format", "vtk", "--cache", cache, "--out", str(out))
    assert r.returncode == 0, r.stderr
    sim = sflsh.Simulation(subject="OPEN_TRAIN_2", motion="shake_hips", frames=3, solver="full", mesh="coarse", cache=cache)
    result = sim.run()
    for t in range(3):
        points, _ = read_vtp(out / f"body_{t:06d}.vtp")
        np.testing.assert_allclose(result["vertices"][t], points, rtol=0, atol=1e-9)
    cli_summary = json.loads((out / "summary.json").read_text())
    assert sim.summary()["solver"] == cli_summary["solver"]


def test_step_by_step_equals_run(simulation, cache):
    other = sflsh.Simulation(**SETTINGS, cache=cache)
    assert simulation.frame == 0 and simulation.num_frames == FRAMES and not simulation.finished
    for expected in range(1, FRAMES):
        assert simulation.step() == expected
    assert simulation.finished
    np.testing.assert_array_equal(simulation.vertices(), other.run()["vertices"][-1])
    with pytest.raises(sflsh.Error, match="last"):
        simulation.step()


def test_arrays(simulation):
    x, w = simulation.state()
    assert x.shape == w.shape and x.shape[1] == 3
    assert simulation.nodes.shape == x.shape and simulation.tets.shape[1] == 4 and simulation.tets.dtype == np.int32
    assert np.shares_memory(simulation.faces, simulation.faces) and not simulation.faces.flags.writeable
    v = simulation.vertices()
    assert v.shape == (simulation.num_vertices, 3) and v.flags.owndata is False and v.base is not None   # owned by a capsule
    assert not np.shares_memory(v, simulation.vertices())


def test_errors_are_exceptions_with_the_clis_messages(cache):
    with pytest.raises(sflsh.Error, match=r"^--solver bogus: expected full or reduced$"):
        sflsh.Simulation(**{**SETTINGS, "solver": "bogus"}, cache=cache)
    with pytest.raises(sflsh.Error, match="--integrator"):
        sflsh.Simulation(**{**SETTINGS, "integrator": "euler"}, cache=cache)
    with pytest.raises(sflsh.Error, match="--density"):
        sflsh.Simulation(**{**SETTINGS, "density": -1.0}, cache=cache)
    with pytest.raises(sflsh.Error, match="NOBODY"):
        sflsh.Simulation(**{**SETTINGS, "subject": "NOBODY"}, cache=cache)
    # The keywords are the signature's: an unknown one, or no motion, is Python's TypeError showing the signature.
    with pytest.raises(TypeError, match="motion: str"):
        sflsh.Simulation(**SETTINGS, cache=cache, colour="red")
    with pytest.raises(TypeError, match="motion: str"):
        sflsh.Simulation(subject="OPEN_TRAIN_1", solver="reduced")
    with pytest.raises(sflsh.Error, match="--motion is required"):
        sflsh.Simulation(motion="", subject="OPEN_TRAIN_1", solver="reduced")


@pytest.mark.parametrize("option, value, keyword", [("--density", "-1", "density"), ("--subject", "NOBODY", "subject"),
                                                    ("--integrator", "euler", "integrator")])
def test_error_message_is_the_clis_line(cli, cache, scratch, option, value, keyword):
    # The CLI prints "sflsh: error: <message>"; the module raises sflsh.Error(<message>) for the same input.
    args = {"--solver": "reduced", "--mesh": "coarse", "--subject": "OPEN_TRAIN_1", "--motion": "jiggle_on_toes",
            "--frames": str(FRAMES), option: value}
    r = run_cli(cli, "simulate", *[x for kv in args.items() for x in kv], "--cache", cache, "--out", str(scratch / "run"))
    assert r.returncode == 1
    line = [l for l in r.stderr.splitlines() if l.startswith("sflsh: error: ")][0]
    with pytest.raises(sflsh.Error) as raised:
        sflsh.Simulation(**{**SETTINGS, keyword: float(value) if keyword == "density" else value}, cache=cache)
    assert str(raised.value) == line[len("sflsh: error: "):]


def test_keyboard_interrupt_leaves_the_simulation_usable(cache):
    sim = sflsh.Simulation(**{**SETTINGS, "frames": 400}, cache=cache)
    sim.step()   # warm: the first frame factorizes
    timer = threading.Timer(0.3, _thread.interrupt_main)   # as Ctrl-C: SIGINT's handler, seen between frames
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sim.run()
    finally:
        timer.cancel()
    reached = sim.frame
    assert 1 <= reached < 399
    assert sim.step() == reached + 1   # usable: it steps on from the last finished frame
    assert sim.summary()["frames"][-1]["frame"] == reached + 1
