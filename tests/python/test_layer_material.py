"""sflsh.Layer and sflsh.Material: shapes and dtypes, views, the skin map, materials from a file, the shipped shape
model and arrays, and their errors."""
import numpy as np
import pytest

import sflsh


@pytest.fixture(scope="module")
def layer(cache):
    return sflsh.Layer(subject="OPEN_TRAIN_1", thickness=0.5, mesher="layered", mesh="coarse", cache=cache)


def test_layer_arrays(layer):
    nodes, tets = layer.nodes, layer.tets
    assert nodes.ndim == 2 and nodes.shape[1] == 3 and nodes.dtype == np.float64
    assert tets.shape[1] == 4 and tets.dtype == np.int32 and tets.min() >= 0 and tets.max() < len(nodes)
    assert layer.node_parts.shape == (len(nodes),) and layer.tet_parts.shape == (len(tets),)
    assert set(np.unique(layer.tet_parts)) <= {0, 1, 2, 3, 4}
    assert layer.quality["inverted"] == 0 and layer.quality["tets"] == len(tets)
    assert np.shares_memory(layer.nodes, layer.nodes) and not layer.nodes.flags.writeable
    assert layer.template_nodes.shape == nodes.shape


def test_skin_map_gives_the_skin(layer):
    skin = layer.skin_map
    r = len(layer.region_vertices)
    assert skin["tet"].shape == (r,) and skin["bary"].shape == (r, 4) and skin["node"].shape == (r,)
    by_map = np.einsum("rk,rkc->rc", skin["bary"], layer.nodes[layer.tets[skin["tet"]]])
    np.testing.assert_allclose(by_map, layer.skin_positions(), rtol=0, atol=1e-12)


def test_layer_errors(cache):
    with pytest.raises(sflsh.Error, match="--thickness"):
        sflsh.Layer(thickness=1.5, mesher="layered", mesh="coarse", cache=cache)
    with pytest.raises(sflsh.Error, match="exclude"):
        sflsh.Layer(subject="OPEN_TRAIN_1", betas=np.zeros(10), cache=cache)


def test_material_from_the_shipped_shape_model(scratch):
    a = sflsh.Material.from_shape_model(subject="OPEN_TRAIN_1")
    b = sflsh.material_for_beta(sflsh.subject("OPEN_TEST_3"))
    assert a.num_control_points == b.num_control_points > 0
    assert a.kappa.shape == (a.num_control_points, 3) and a.vertices.dtype == np.int32
    assert not np.array_equal(a.kappa, b.kappa)   # κ̂(β) depends on the shape
    path = scratch / "material.toml"
    scratch.mkdir(parents=True, exist_ok=True)
    a.save(str(path))
    c = sflsh.Material(str(path))
    np.testing.assert_array_equal(c.vertices, a.vertices)
    np.testing.assert_allclose(c.kappa, a.kappa, rtol=1e-15)


def test_material_from_arrays():
    m = sflsh.Material.from_arrays([10, 20], [[0.5, 5000.0, 2000.0], [0.4, 6000.0, 2500.0]], subject="mine")
    np.testing.assert_array_equal(m.vertices, [10, 20])
    with pytest.raises(sflsh.Error, match="young_tangent"):
        sflsh.Material.from_arrays([10], [[0.5, -5.0, 2000.0]])
    with pytest.raises(sflsh.Error, match="missing.toml"):
        sflsh.Material("/tmp/sflsh_tests/python/missing.toml")


def test_simulation_takes_a_material_object(cache):
    material = sflsh.Material.from_shape_model(subject="OPEN_TEST_3")
    sim = sflsh.Simulation(subject="OPEN_TEST_3", motion="shake_hips", frames=3, solver="reduced", mesh="coarse",
                           material=material, cache=cache)
    sim.run()
    assert sim.summary()["material"]["control_points"] == material.num_control_points
