"""A new user's first commands: ``biotac-bench`` alone prints the help (which lists the commands) besides its
error, ``--version`` names the installed version, and a bare value where a flag is needed says which flag."""

from __future__ import annotations

from importlib.metadata import version

from bench.cli import main as cli


def test_no_command_prints_the_help_and_says_what_is_missing(capsys):
    assert cli.main([]) == 2
    out, err = capsys.readouterr()
    assert "typical session:" in out and "campaign" in out and "required: COMMAND" in err


def test_version_names_the_installed_package(capsys):
    try:
        cli.main(["--version"])
    except SystemExit as e:
        assert e.code == 0
    assert capsys.readouterr().out.strip() == f"biotac-bench {version('biotac-bench')}"


def test_a_bare_seed_or_texture_number_points_to_its_flag(capsys):
    assert cli.main(["units", "17"]) == 2
    assert "biotac-bench units --seed 17" in capsys.readouterr().err
    assert cli.main(["textures", "30"]) == 2
    assert "biotac-bench textures --show 30" in capsys.readouterr().err
