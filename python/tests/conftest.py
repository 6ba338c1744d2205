"""Shared fixtures: paths to bundled data and a runner for the lasercell CLI, whose output on the
same files is what the bindings are compared with."""

import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def source_dir():
    path = os.environ.get("LASERCELL_SOURCE_DIR")
    if not path:
        pytest.fail("LASERCELL_SOURCE_DIR is not set (ctest sets it; see tests/CMakeLists.txt)")
    return path


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("LASERCELL_CLI")
    if not path:
        pytest.fail("LASERCELL_CLI is not set (ctest sets it; see tests/CMakeLists.txt)")

    def run(*args):
        done = subprocess.run([path, *args], capture_output=True, text=True, check=False)
        assert done.returncode == 0, done.stderr
        return done.stdout

    return run


@pytest.fixture(scope="session")
def uwa_model(source_dir):
    return os.path.join(source_dir, "datasets/real/uwa/parasaurolophus_6700.bin.ply")


@pytest.fixture(scope="session")
def demo_cell(source_dir):
    return os.path.join(source_dir, "datasets/demo/cell.yaml")
