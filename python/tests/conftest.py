"""Fixtures of the Python module's tests: the crane in the plant (robots/, always there) and the Panda
in a MotionBenchMaker bookshelf (the shared data: RASTERCHECK_DATA, else ../shared/data; skipped
when absent)."""
import os
import pathlib

import pytest

SOURCE = pathlib.Path(os.environ.get("RASTERCHECK_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def data_root():
    root = os.environ.get("RASTERCHECK_DATA") or os.environ.get("RASTERCHECK_DEFAULT_DATA") \
        or str(SOURCE.parent / "shared" / "data")
    return pathlib.Path(root) if pathlib.Path(root).is_dir() else None


@pytest.fixture(scope="session")
def rc():
    try:
        import rastercheck
    except ImportError as error:  # built by CMake into build/python; ctest sets PYTHONPATH
        pytest.fail(f"cannot import rastercheck ({error}): run with PYTHONPATH=build/python")
    return rastercheck


@pytest.fixture(scope="session")
def crane(rc):
    """The crane lifting a skid in the plant, with the lift's start and goal."""
    return rc.load(SOURCE / "robots/crane/crane.urdf", srdf=SOURCE / "robots/crane/crane.srdf",
                   scene=SOURCE / "robots/sites/plant.yaml", request=SOURCE / "robots/sites/plant_lift.yaml")


@pytest.fixture(scope="session")
def crane_checker(rc, crane):
    return rc.Checker(crane, threads=1)


@pytest.fixture(scope="session")
def panda_dir():
    root = data_root()
    if root is None:
        pytest.skip("no shared data (RASTERCHECK_DATA or ../shared/data): the Panda tests are skipped")
    return root / "mbm" / "panda"


@pytest.fixture(scope="session")
def bookshelf(rc, panda_dir):
    """The Panda in MotionBenchMaker's bookshelf_small scene 1, with request 1's start and goal."""
    problem = panda_dir / "problems" / "bookshelf_small_panda"
    return rc.load(panda_dir / "panda.urdf", srdf=panda_dir / "panda.srdf", scene=problem / "scene0001.yaml",
                   request=problem / "request0001.yaml")


@pytest.fixture(scope="session")
def panda_checker(rc, bookshelf):
    return rc.Checker(bookshelf, threads=1)
