"""Where the examples find the MotionBenchMaker Panda: $RASTERCHECK_DATA, else ../shared/data beside
the repository."""
import os
import pathlib
import sys

REPOSITORY = pathlib.Path(__file__).resolve().parents[2]


def panda_files(scenario="bookshelf_small", index=1):
    """(urdf, srdf, scene, request) of a MotionBenchMaker Panda problem."""
    root = pathlib.Path(os.environ.get("RASTERCHECK_DATA") or REPOSITORY.parent / "shared" / "data")
    panda = root / "mbm" / "panda"
    if not panda.is_dir():
        sys.exit(f"no MotionBenchMaker data at {panda}: set RASTERCHECK_DATA")
    problem = panda / "problems" / f"{scenario}_panda"
    return panda / "panda.urdf", panda / "panda.srdf", problem / f"scene{index:04d}.yaml", \
        problem / f"request{index:04d}.yaml"
