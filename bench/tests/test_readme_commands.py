"""The README's two commands and what stands behind them: command 1 (``./scripts/demo``) runs end to end and writes
what the README lists; ``.ci/run`` runs command 2 (``./scripts/test``), which writes JUnit XML; tox's groups are
the suite's registered markers.  (The set-up inside both scripts is a no-op once ``.venv`` matches the lock.)"""

import json
import re
import subprocess
import tomllib

import pytest

from bench.paths import REPO
from bench.tests.cli_runs import CLI

pytestmark = pytest.mark.unit


def test_command_1_runs_the_demo_end_to_end(tmp_path):
    """README: `./scripts/demo` runs the sphere-drop scene end to end: report.md, record.json, codes.npz, plots."""
    out = tmp_path / "demo"
    r = subprocess.run([str(REPO / "scripts" / "demo"), "--out", str(out), "--quiet"], capture_output=True,
                       text=True, timeout=600, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert {"report.md", "record.json", "codes.npz", "traces.png", "spectrogram.png"} <= {p.name for p in out.iterdir()}
    record = json.loads((out / "record.json").read_text())
    assert record["status"] == "ok" and record["scene"]["source"] == "fixtures/scenes/sphere_drops.toml"
    spheres = record["impact_detection"]["spheres"]
    assert len(spheres) == 6 and all(s["drops"] == 10 for s in spheres.values())


def test_ci_runs_exactly_the_readmes_test_command():
    """`.ci/run` runs command 2, which is the README's second command, and that writes out/test-results.xml."""
    readme = (REPO / "README.md").read_text()
    commands = re.findall(r"^\./scripts/(\w+)\s+# (\d)\.", readme, flags=re.M)
    assert commands == [("demo", "1"), ("test", "2")]
    ci = [line for line in (REPO / ".ci" / "run").read_text().splitlines() if line and not line.startswith("#")]
    assert ci[-1] == "exec ./scripts/test"
    assert "-m pytest --junitxml=out/test-results.xml" in (REPO / "scripts" / "test").read_text()


def test_tox_groups_are_the_registered_markers():
    """tox.ini's groups select the markers pyproject registers (strict markers: a typo would select nothing)."""
    registered = {m.split(":")[0] for m in
                  tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]["markers"]}
    groups = dict(re.findall(r"^\s+(\w+): pytest -m (\w+)", (REPO / "tox.ini").read_text(), flags=re.M))
    assert groups and all(name == marker for name, marker in groups.items())
    assert set(groups) | {"mutants"} == registered


def test_the_readmes_scene_error_is_what_a_run_prints(tmp_path):
    """README, Scenes: the example of a scene refused with every problem named is the command's own output, word
    for word (a scene with those two problems: a 99 999 Hz vibration and a channel QQQ), with exit status 2."""
    readme = (REPO / "README.md").read_text()
    example = re.search(r"```\n(error: bad\.toml: .*?)```", readme, flags=re.S).group(1)
    (tmp_path / "bad.toml").write_text('[scene]\nname = "bad"\nduration_s = 1.0\n[host]\nsequence = ["PAC", "QQQ"]\n'
                                       '[[stimulus]]\nkind = "vibration"\nfrequency_Hz = 99999\namplitude_um = 1.0\n'
                                       'start_s = 0.1\nduration_s = 0.5\n')
    r = subprocess.run([*CLI, "run", "bad.toml", "--out", "o"],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert (r.returncode, r.stderr) == (2, example)


def test_scripts_claims_writes_a_relative_plots_folder_where_the_user_is(tmp_path):
    """``scripts/claims --plots DIR`` from any folder: DIR is relative to where the user runs it (the script used to
    change to the repository first, so the plot landed in the checkout)."""
    r = subprocess.run([str(REPO / "scripts" / "claims"), "--only", "vibration", "--quick", "--plots", "mine"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "mine" / "frequency_sensitivity.png").stat().st_size > 1000
    assert not (REPO / "mine").exists()


#: a README example's placeholder for the user's own file (not a file of the repository)
OWN_FILE_PLACEHOLDERS = {"my_scene.toml"}


def readme_cli_examples() -> list[list[str]]:
    """The arguments of every ``.venv/bin/biotac-bench …`` line in the README's code blocks (its comment cut)."""
    import shlex

    readme = (REPO / "README.md").read_text()
    blocks = re.findall(r"^```[a-z]*\n(.*?)^```", readme, flags=re.S | re.M)
    return [shlex.split(line.split(" # ")[0], comments=False)[1:]
            for block in blocks for line in block.splitlines() if line.startswith(".venv/bin/biotac-bench ")]


def test_every_command_line_the_readme_shows_is_one_the_cli_takes():
    """Each example in the README's code blocks names a real subcommand and only options it has, with values it
    takes (parsed by the CLI's own parser, nothing run), and every repository file it names exists: a renamed flag
    or file cannot leave the README behind."""
    from bench.cli.main import build_parser

    examples = readme_cli_examples()
    assert len(examples) >= 15, examples
    parser = build_parser()
    for argv in examples:
        try:
            _, extra = parser.parse_known_args(argv)
        except SystemExit as e:
            pytest.fail(f"the README's `biotac-bench {' '.join(argv)}` is refused by the CLI (exit {e.code})")
        assert not extra, (argv, extra)
        files = [a for a in argv if a.endswith((".toml", ".json")) and a not in OWN_FILE_PLACEHOLDERS]
        assert all((REPO / f).is_file() for f in files), (argv, files)
