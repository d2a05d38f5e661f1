"""The module shows itself: real signatures (keyword arguments with their defaults) for inspect.signature() and help(),
docstrings on every function, method and property, sflsh.__version__ as the command line's, and the type stub
(python/sflsh.pyi, installed beside the module) current and in agreement with the module's names and signatures.
"""
import ast
import importlib.util
import inspect
import pathlib
import subprocess

import pytest

import sflsh

ROOT = pathlib.Path(__file__).resolve().parents[2]
STUB = ROOT / "python" / "sflsh.pyi"


def public(namespace):
    return {n: v for n, v in namespace.items() if not n.startswith("_")}


def test_simulation_signature_has_the_clis_options_and_defaults():
    sig = inspect.signature(sflsh.Simulation)
    p = sig.parameters
    assert p["motion"].kind is inspect.Parameter.KEYWORD_ONLY and p["motion"].default is inspect.Parameter.empty
    assert all(x.kind is inspect.Parameter.KEYWORD_ONLY for x in p.values())
    expected = {"subject": None, "betas": None, "solver": "full", "frames": 0, "fps": 60.0, "substeps": 1,
                "mesh": "default", "mesher": "layered", "control_points": 12, "density": 1000.0, "gravity": False,
                "mass": "consistent", "integrator": "bdf2", "handles": 86, "cubature": -1,
                "cubature_weights": "nnls", "newton_tolerance": 1e-5, "allow_long": False, "record": True,
                "energies": False}
    for name, default in expected.items():
        assert p[name].default == default, name
    write = inspect.signature(sflsh.Simulation.write).parameters
    assert list(write)[:2] == ["self", "dir"] and write["format"].default == "xdmf"  # as `simulate --format`
    assert write["precision"].default == "float32"
    assert list(inspect.signature(sflsh.Layer).parameters)[:2] == ["subject", "betas"]
    assert inspect.signature(sflsh.Motion).parameters["fps"].default == 60.0
    # A bound method's signature starts after self.
    assert list(inspect.signature(sflsh.Body().shape).parameters) == ["betas"]


def test_help_shows_the_signature_and_the_units():
    text = subprocess.run(["/usr/bin/python3", "-c", "import sflsh; help(sflsh.Simulation)"], capture_output=True,
                          text=True, check=True).stdout
    assert "motion: str" in text and "solver: str = 'full'" in text and "fps: float = 60.0" in text
    assert "[m]" in text and "[s]" in text


def test_every_function_method_and_property_has_a_signature_and_a_docstring():
    for name, value in public(vars(sflsh)).items():
        if inspect.isclass(value):
            if issubclass(value, BaseException):
                continue
            inspect.signature(value)  # raises when there is none
            for member_name, member in public(vars(value)).items():
                where = f"{name}.{member_name}"
                if type(member).__name__ == "pybind11_static_property":
                    continue  # CPython 3.11 drops a property subclass's docstring (Body.joint_names: the class's)
                if isinstance(member, property):
                    doc = member.__doc__ or ""
                    assert doc and not doc.startswith("("), f"{where}: no docstring"
                else:
                    function = getattr(value, member_name)
                    inspect.signature(function)
                    assert function.__doc__.split("\n", 2)[-1].strip(), f"{where}: no docstring"
        elif callable(value):
            inspect.signature(value)
            assert value.__doc__.split("\n", 2)[-1].strip(), f"{name}: no docstring"


def test_version_is_the_command_lines(cli):
    r = subprocess.run([cli, "--version"], capture_output=True, text=True, check=True)
    assert sflsh.__version__ and sflsh.__version__ in r.stdout


def load_generator():
    spec = importlib.util.spec_from_file_location("generate_stub", ROOT / "scripts" / "generate_stub.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_stub_is_current_and_installed_beside_the_module():
    text = STUB.read_text()
    assert load_generator().generate(sflsh) == text, "python/sflsh.pyi is stale: run scripts/generate_stub.py"
    beside = pathlib.Path(sflsh.__file__).with_name("sflsh.pyi")
    assert beside.read_text() == text


def stub_functions(tree):
    """{"name" or "Class.name": ast.FunctionDef} of the stub, and its class names."""
    functions, classes = {}, set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            functions[node.name] = node
        elif isinstance(node, ast.ClassDef):
            classes.add(node.name)
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    functions[f"{node.name}.{item.name}"] = item
                elif isinstance(item, ast.AnnAssign):
                    functions[f"{node.name}.{item.target.id}"] = item
    return functions, classes


def stub_parameters(node):
    """[(name, kind, default)] of a stub function, as inspect names the kinds."""
    a = node.args
    out = [(x.arg, inspect.Parameter.POSITIONAL_OR_KEYWORD) for x in a.posonlyargs + a.args]
    defaults = [inspect.Parameter.empty] * (len(out) - len(a.defaults)) + [ast.literal_eval(d) for d in a.defaults]
    out = [(n, k, d) for (n, k), d in zip(out, defaults)]
    for x, d in zip(a.kwonlyargs, a.kw_defaults):
        out.append((x.arg, inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.empty if d is None else ast.literal_eval(d)))
    return out


def module_parameters(function, method):
    params = list(inspect.signature(function).parameters.values())
    out = []
    for p in params:
        kind = inspect.Parameter.POSITIONAL_OR_KEYWORD if p.kind is inspect.Parameter.POSITIONAL_ONLY else p.kind
        out.append((p.name, kind, p.default))
    return out


def test_the_stub_names_every_function_with_the_modules_signature():
    functions, classes = stub_functions(ast.parse(STUB.read_text()))
    seen = set()
    for name, value in public(vars(sflsh)).items():
        if inspect.isclass(value):
            assert name in classes, f"class {name} missing from the stub"
            if issubclass(value, BaseException):
                continue
            for member_name in public(vars(value)) | {"__init__": None}:
                key = f"{name}.{member_name}"
                assert key in functions, f"{key} missing from the stub"
                seen.add(key)
                node = functions[key]
                member = vars(value)[member_name]
                if isinstance(member, property) or isinstance(node, ast.AnnAssign):
                    continue
                if isinstance(member, staticmethod):
                    assert stub_parameters(node) == module_parameters(getattr(value, member_name), False), key
                else:
                    assert stub_parameters(node) == module_parameters(getattr(value, member_name), True), key
        elif callable(value):
            assert name in functions, f"{name} missing from the stub"
            seen.add(name)
            assert stub_parameters(functions[name]) == module_parameters(value, False), name
    assert set(functions) == seen, f"the stub names what the module lacks: {set(functions) - seen}"
