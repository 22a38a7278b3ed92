"""Shared set-up of the nbv Python tests: the command line beside the package, and the
standard workload bunny-3 built once by it."""
import os
import subprocess

import pytest

import nbv


def nbv_cli():
    path = os.environ.get("NBV_CLI")
    if not path:
        pytest.skip("NBV_CLI names no nbv binary (ctest sets it)")
    return path


def run_cli(*args):
    """Runs the nbv command; its stdout, or a test failure with its stderr."""
    done = subprocess.run([nbv_cli(), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, f"nbv {' '.join(map(str, args))}: {done.stderr}"
    return done.stdout


@pytest.fixture(scope="session")
def bunny3(tmp_path_factory):
    """The bunny-3 map as `nbv workload` writes it, and its path."""
    path = tmp_path_factory.mktemp("bunny3") / "bunny3.vdb"
    run_cli("workload", "--name", "bunny-3", "--map", path)
    return nbv.load_map(str(path)), path
