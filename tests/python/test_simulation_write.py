"""Simulation.write(dir, format=…) writes the run folder `sflsh simulate` writes for the same inputs: the same files,
the same frames (points and arrays to round-off of the threaded cubature sums), the same σ map and the same
summary.json entries; xdmf and every N-th frame as the command's options; record=False keeps no frames to write.
"""
import json

import numpy as np
import pytest

import sflsh
from conftest import read_vtp, run_cli

FRAMES = 6
SETTINGS = dict(subject="OPEN_TRAIN_1", motion="jiggle_on_toes", frames=FRAMES, solver="reduced", mesh="coarse")
CLI_SETTINGS = ["simulate", "--solver", "reduced", "--mesh", "coarse", "--subject", "OPEN_TRAIN_1", "--motion",
                "jiggle_on_toes", "--frames", str(FRAMES)]


def files(folder):
    return sorted(p.name for p in folder.iterdir())


def test_write_gives_the_clis_run_folder(cli, cache, scratch):
    r = run_cli(cli, *CLI_SETTINGS, "--format", "vtk", "--write-layer", "--cache", cache, "--out", str(scratch / "cli"))
    assert r.returncode == 0, r.stderr
    sim = sflsh.Simulation(**SETTINGS, cache=cache)
    sim.run()
    sim.write(scratch / "python", format="vtk", write_layer=True)
    assert files(scratch / "python") == files(scratch / "cli")
    # The defaults agree too: the compact xdmf series (Float32, zlib, the display arrays) on both sides.
    r = run_cli(cli, *CLI_SETTINGS, "--cache", cache, "--out", str(scratch / "cli_default"))
    assert r.returncode == 0, r.stderr
    sim.write(scratch / "python_default")
    assert files(scratch / "python_default") == files(scratch / "cli_default") == [
        "body.h5", "body.xmf", "dynamics.vtp", "summary.json"]
    default_output = [json.loads((scratch / f / "summary.json").read_text())["output"]
                      for f in ("python_default", "cli_default")]
    assert default_output[0] == default_output[1]
    assert default_output[0]["precision"] == "float32" and default_output[0]["compression"] == "zlib"
    for t in range(FRAMES):
        mine, theirs = read_vtp(scratch / "python" / f"body_{t:06d}.vtp"), read_vtp(scratch / "cli" / f"body_{t:06d}.vtp")
        np.testing.assert_allclose(mine[0], theirs[0], rtol=0, atol=1e-9)
        assert set(mine[1]) == set(theirs[1])
        for name in mine[1]:
            np.testing.assert_allclose(mine[1][name], theirs[1][name], rtol=1e-6, atol=1e-9, err_msg=name)
    _, dynamics = read_vtp(scratch / "python" / "dynamics.vtp")
    _, expected = read_vtp(scratch / "cli" / "dynamics.vtp")
    np.testing.assert_allclose(dynamics["sigma"], expected["sigma"], rtol=0, atol=1e-6)   # mm
    mine = json.loads((scratch / "python" / "summary.json").read_text())
    theirs = json.loads((scratch / "cli" / "summary.json").read_text())
    assert set(mine) == set(theirs)
    for key in ("command", "solver", "integrator", "mass", "subject", "beta", "motion", "mesh", "material", "output"):
        assert mine[key] == theirs[key], key
    assert mine["dynamics"]["sigma_mean_mm"] == pytest.approx(theirs["dynamics"]["sigma_mean_mm"], rel=1e-9)
    assert (scratch / "python" / "layer.pvd").read_text() == (scratch / "cli" / "layer.pvd").read_text()


def test_write_xdmf_every_and_refusals(cli, cache, scratch):
    sim = sflsh.Simulation(**SETTINGS, cache=cache)
    sim.run(3)   # a run stopped early writes the frames so far, the last one included
    sim.write(str(scratch / "xdmf"), format="xdmf", precision="float32")
    assert files(scratch / "xdmf") == ["body.h5", "body.xmf", "dynamics.vtp", "summary.json"]
    summary = json.loads((scratch / "xdmf" / "summary.json").read_text())
    assert summary["output"]["format"] == "xdmf" and summary["output"]["precision"] == "float32"
    assert summary["dynamics"]["frames"] == 4
    sim.write(scratch / "every", format="vtk", every=2)
    assert [n for n in files(scratch / "every") if n.startswith("body_")] == [
        "body_000000.vtp", "body_000002.vtp", "body_000003.vtp"]
    with pytest.raises(sflsh.Error, match="--format"):
        sim.write(scratch / "bad", format="vtu")
    assert not (scratch / "bad").exists()   # nothing written
    quiet = sflsh.Simulation(**SETTINGS, cache=cache, record=False)
    quiet.step()
    assert quiet.recorded_frames == 0
    with pytest.raises(sflsh.Error, match="record=False"):
        quiet.write(scratch / "none")


def test_fields_choose_the_frames_arrays_as_in_the_cli(cli, cache, scratch):
    # `simulate --fields` (as a scene's [output] fields) and write(fields=…): only those arrays in the frames.
    fields = ["soft_tissue_displacement", "Normals"]
    r = run_cli(cli, *CLI_SETTINGS, "--format", "vtk", "--fields", ",".join(fields), "--cache", cache, "--out",
                str(scratch / "cli"))
    assert r.returncode == 0, r.stderr
    sim = sflsh.Simulation(**SETTINGS, cache=cache)
    sim.run()
    sim.write(scratch / "python", format="vtk", fields=fields)
    for folder in ("cli", "python"):
        _, arrays = read_vtp(scratch / folder / "body_000003.vtp")
        assert sorted(arrays) == sorted(fields), folder
        assert json.loads((scratch / folder / "summary.json").read_text())["output"]["fields"] == fields
    r = run_cli(cli, *CLI_SETTINGS, "--fields", "sigma", "--cache", cache, "--out", str(scratch / "bad"))
    assert r.returncode == 1 and "--fields: unknown field 'sigma'" in r.stderr
