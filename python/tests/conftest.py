"""Shared fixtures: the `tcomp` command line the binding is compared with, and simulated runs.

The CLI is the repository's build (`target/debug/tcomp`, made by `cargo xtask ci` before the
Python tests run) or the one `TCOMP_CLI` names; every run of it has a timeout.
"""

import os
import pathlib
import subprocess

import pytest

import tcomp

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cli_path() -> str:
    path = os.environ.get("TCOMP_CLI") or str(ROOT / "target" / "debug" / "tcomp")
    if not os.path.exists(path):
        pytest.fail(f"the tcomp CLI is not built at {path} (cargo build -p tcomp, or set TCOMP_CLI)")
    return path


@pytest.fixture(scope="session")
def cli():
    """Runs `tcomp ARGS...` in a directory, with a timeout; returns the completed process."""

    def run(args, cwd, check=True, timeout=300):
        p = subprocess.run([cli_path(), *args], cwd=cwd, capture_output=True, text=True, timeout=timeout)
        if check and p.returncode != 0:
            raise AssertionError(f"tcomp {' '.join(args)} failed:\n{p.stderr}")
        return p

    return run


@pytest.fixture(scope="session")
def ifog(tmp_path_factory):
    """The IFOG preset with a Shupe term, simulated once through the binding."""
    d = tmp_path_factory.mktemp("sim")
    return tcomp.simulate("ifog-shupe", out=d / "ifog")


IFOG_FIT = dict(
    target="gyro_dph",
    reference="ref_dph",
    signal="T=t_coil_c",
    feature=["T", "rate(T)", "T * rate(T)", "lag(T, 2400)"],
    centers=32,
    sensor="ifog",
    axis="x",
    unit="deg/h",
)


@pytest.fixture(scope="session")
def ifog_model(ifog):
    return tcomp.fit(ifog.train, source=os.path.join(ifog.dir, "train.csv"), **IFOG_FIT)
