"""The command line starts light: building the parser and printing any command's --help loads none of the heavy
stack (scipy, numba, matplotlib, dask, h5py, the sensor model); each command imports what it needs when it runs.
The help texts take their defaults and choices from light modules, which must agree with the heavy ones."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit
REPO = Path(__file__).resolve().parents[2]
HEAVY = ("scipy", "numba", "matplotlib", "dask", "h5py", "emulator.sensor")

#: In a fresh interpreter: build the parser, format the help of the main parser and of every (sub)command, and print
#: which heavy modules got loaded on the way, per command (a command's help is formatted after all those before it,
#: so the first command listing a module is the one that loaded it).
_HELP_SCRIPT = """
import argparse, json, sys
from bench.cli.main import build_parser

HEAVY = {heavy!r}
SKIP = {skip!r}

def walk(parser, path):
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from walk(sub, path + [name])

loaded = {{}}
for path, parser in walk(build_parser(), []):
    if " ".join(path) not in SKIP:
        parser.format_help()
    loaded[" ".join(path) or "biotac-bench"] = [m for m in HEAVY if m in sys.modules]
print(json.dumps(loaded))
"""


def _heavy_modules_after_help(skip=()) -> dict[str, list[str]]:
    """Command -> the heavy modules loaded once its help (and that of every command before it) was formatted."""
    script = _HELP_SCRIPT.format(heavy=HEAVY, skip=tuple(skip))
    done = subprocess.run([sys.executable, "-c", script], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_every_help_but_campaigns_loads_no_heavy_module():
    loaded = _heavy_modules_after_help(skip=("campaign",))
    assert len(loaded) >= 18  # the main parser, every command and cheetah's serve
    assert {command: modules for command, modules in loaded.items() if modules} == {}


def test_campaign_help_loads_no_heavy_module():
    """Its faults and scenes come from bench.campaigns.case_names (light), not from the registries of
    bench.campaigns.faults (emulator stimuli, the bridge)."""
    assert _heavy_modules_after_help()["campaign"] == []


def test_the_command_line_runs_with_a_fresh_interpreter():
    """``python -m bench.cli --help`` (what the biotac-bench script runs) prints the commands and exits 0."""
    done = subprocess.run([sys.executable, "-m", "bench.cli", "--help"], cwd=REPO, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and "texture-sweep" in done.stdout and done.stderr == ""


# --- the light modules agree with the heavy ones ------------------------------------------------------------------


def test_claims_only_offers_exactly_the_registered_groups_in_order():
    from bench.verification.claim_names import CLAIM_GROUP_NAMES
    from bench.verification.claims import CLAIM_GROUPS

    assert CLAIM_GROUP_NAMES == tuple(CLAIM_GROUPS)


def test_moved_constants_have_one_definition_reexported_where_they_were():
    from bench.experiments import design, experiment, trials
    from bench.scenes import limits, scene

    assert trials.PILOT_WORTH_TRIALS is design.PILOT_WORTH_TRIALS == 60
    assert experiment.ABLATIONS is design.ABLATIONS
    assert experiment.ExperimentSpec().pilot_textures == list(design.D_PILOT_TEXTURES)
    assert scene.MAX_SENSORS is limits.MAX_SENSORS == 5


def test_the_emulator_package_still_offers_sensor_and_params():
    import emulator
    from emulator.params import SensorParams
    from emulator.sensor import Sensor

    assert emulator.Sensor is Sensor and emulator.SensorParams is SensorParams
    assert {"Sensor", "SensorParams"} <= set(dir(emulator))
    with pytest.raises(AttributeError, match="no attribute 'Nonexistent'"):
        emulator.Nonexistent  # noqa: B018


def test_a_numerical_error_is_still_reported_in_one_line_with_status_2(monkeypatch, capsys):
    """main() names NumericalError among the bad-input errors only once emulator.adc is loaded; once raised
    (its module necessarily loaded), it is still one line on stderr and exit status 2."""
    from bench.cli import main as cli_main
    from bench.cli import scenes
    from emulator.adc import NumericalError

    def fails(_args):
        raise NumericalError("non-finite value nan at PAC (conversion #3)")

    monkeypatch.setattr(scenes, "_cmd_profiles", fails)
    assert cli_main.main(["profiles"]) == 2
    assert capsys.readouterr().err == "error: non-finite value nan at PAC (conversion #3)\n"


def test_the_console_script_imports_nothing_heavy_before_main_runs():
    """The `biotac-bench` script imports bench.cli.main, then calls main(): the command modules (numpy, the
    emulator) load inside main, whose Ctrl-C handling covers them — a Ctrl-C in the first tenth of a second printed
    a traceback through numpy's import."""
    code = "import sys, bench.cli.main; print(json.dumps(sorted(m for m in ('numpy', 'emulator', 'bench.cli.args', 'tempfile') if m in sys.modules)))"
    out = subprocess.run([sys.executable, "-c", "import json; " + code], capture_output=True, text=True, cwd=REPO,
                         timeout=60)
    assert json.loads(out.stdout) == [], out.stderr


def test_a_ctrl_c_while_the_commands_load_is_one_line(monkeypatch, capsys):
    from bench.cli import main as cli_main

    def loading():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_main, "command_groups", loading)
    assert cli_main.main(["scenes"]) == 130
    assert capsys.readouterr().err == "interrupted\n"
