import json
import os
import subprocess
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def cli():
    exe = os.environ.get("PARTICLEMESH_CLI")
    if not exe or not Path(exe).exists():
        pytest.skip("PARTICLEMESH_CLI is not set to the built particlemesh binary")

    def run(*args, check=True, timeout=300):
        proc = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, timeout=timeout)
        if check and proc.returncode != 0:
            raise AssertionError(f"particlemesh {' '.join(map(str, args))} failed ({proc.returncode}):\n{proc.stderr}")
        return proc

    return run


@pytest.fixture(scope="session")
def data_dir():
    d = os.environ.get("PM_TEST_DATA")
    if not d or not Path(d).is_dir():
        pytest.skip("shared test data not found (set PM_TEST_DATA to the shared/data folder)")
    return Path(d)


@pytest.fixture()
def inspect(cli):
    def run(path):
        return json.loads(cli("inspect", path, "--json").stdout)

    return run
