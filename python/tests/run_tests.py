"""Runs the Python module's pytest suite for ctest: exit 77 (skipped) when pytest or numpy is missing."""
import sys

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as missing:
    print(f"skipped: {missing.name} is missing (install python3-pytest and python3-numpy)")
    sys.exit(77)

sys.exit(pytest.main(sys.argv[1:]))
