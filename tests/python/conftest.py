"""Shared fixtures of the Python module's tests (CTest label `python`, tests/CMakeLists.txt).

CTest sets PYTHONPATH to the module's build folder, SFLSH_CLI to the sflsh executable and SFLSH_TEST_CACHE to the
build tree's test cache (template meshes and reduced models shared with the C++ tests). Scratch folders live under
/tmp/sflsh_tests/python/.
"""
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import sflsh

SCRATCH = pathlib.Path("/tmp/sflsh_tests/python")


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("SFLSH_CLI", "")
    if not path:
        pytest.skip("SFLSH_CLI is not set (run the tests through CTest)")
    return path


@pytest.fixture(scope="session")
def cache():
    path = pathlib.Path(os.environ.get("SFLSH_TEST_CACHE", SCRATCH / "cache"))
    path.mkdir(parents=True, exist_ok=True)
    return str(path)


@pytest.fixture()
def scratch(request):
    path = SCRATCH / request.node.name
    shutil.rmtree(path, ignore_errors=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def run_cli(cli, *args):
    """Runs `sflsh -q ARGS…`; returns the completed process (output captured)."""
    return subprocess.run([cli, "-q", *args], capture_output=True, text=True, check=False)


def read_vtp(path):
    """Points and point data of a .vtp file (VTK's own reader: the frames are LZ4-compressed, Float64)."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy

    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    poly = reader.GetOutput()
    points = vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)
    data = poly.GetPointData()
    fields = {data.GetArrayName(i): vtk_to_numpy(data.GetArray(i)) for i in range(data.GetNumberOfArrays())}
    return points, fields
