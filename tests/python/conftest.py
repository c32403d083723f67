"""Fixtures of the Python module's tests: the demlab executable (DEMLAB_EXE, set by CTest, or
build/demlab), the repository root, and one small run made by the CLI that several tests
compare against."""
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.environ.get("DEMLAB_EXE", os.path.join(ROOT, "build", "demlab"))
SCENARIO = os.path.join(ROOT, "scenarios", "geometry-A.toml")
# geometry A at scale 20 (364 discs) for 0.3 s: a release, the gate lifting, the front on the slope
SMALL = {"release.scale": 20, "stop.t_max": 0.3}
SMALL_SET = ["--set", "release.scale=20", "--set", "stop.t_max=0.3"]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def exe():
    return EXE


@pytest.fixture(scope="session")
def cli_run(tmp_path_factory):
    """the small run made by `demlab run` (no plots)"""
    out = str(tmp_path_factory.mktemp("cli") / "run")
    subprocess.run([EXE, "run", SCENARIO, "--out", out, "--no-plots", *SMALL_SET], check=True,
                   stdout=subprocess.DEVNULL)
    return out
