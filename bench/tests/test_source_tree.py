"""A copy of the bench's packages installed without its source tree (a plain ``pip install`` of the clone copies its
Python files only) is refused in one line naming what it lacks and how to install it — by the command line and by
the pytest plugin's factories; it had run on until a file was missing: a FileNotFoundError traceback from deep in
the sensor (the plugin), or "error: max() arg is an empty sequence" (``biotac-bench scenes``)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

from bench.paths import REPO

pytestmark = pytest.mark.firmware
pytest_plugins = ["pytester"]

PROBLEM = ("this copy of biotac-bench ({copy}) lacks fixtures/electrodes.csv, firmware_tests/firmware/bt_bridge.c, "
           "emulator/rtl/biotac_spi.v, emulator/cheetah/cheetah_emu.c: it reads its source tree while it runs, so it "
           "runs from a clone only — install the clone with 'pip install -e /path/to/biotac-bench' (as "
           "./scripts/setup does) or use the clone's .venv (README, Set-up)")


@pytest.fixture
def python_files_only(tmp_path):
    """The bench's packages as a plain ``pip install`` leaves them: their Python files, nothing else."""
    copy = tmp_path / "site"
    def not_python(folder, names):
        return [n for n in names if n in ("__pycache__", "tests")
                or not (n.endswith(".py") or os.path.isdir(os.path.join(folder, n)))]

    for package in ("bench", "emulator"):
        shutil.copytree(REPO / package, copy / package, ignore=not_python)
    return copy


def test_the_command_line_refuses_a_copy_without_its_source_tree(python_files_only, tmp_path):
    run = subprocess.run([sys.executable, "-m", "bench.cli.main", "scenes"], cwd=tmp_path, capture_output=True,
                         text=True, env={"PYTHONPATH": str(python_files_only), "PATH": "/usr/bin:/bin"}, timeout=120)
    assert run.returncode == 2, run
    assert run.stderr == f"biotac-bench scenes: error: {PROBLEM.format(copy=python_files_only)}\n"
    assert run.stdout == ""


def test_the_plugin_fails_the_users_test_in_one_line_on_a_copy_without_its_source_tree(pytester, python_files_only,
                                                                                       monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(python_files_only))
    pytester.makepyfile(test_user="def test_mine(biotac_serial_port):\n    pass\n\n"
                                  "def test_sensor(biotac_sensor):\n    biotac_sensor()\n")
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(errors=1, failed=1)
    problem = PROBLEM.format(copy=python_files_only)
    result.stdout.fnmatch_lines([f"biotac_bridge(): {problem}", f"biotac_sensor(): {problem}"])
    assert "Traceback" not in result.stdout.str() and "FileNotFoundError" not in result.stdout.str()


def test_the_clone_itself_is_complete():
    from bench.paths import source_tree_problem

    assert source_tree_problem() is None
