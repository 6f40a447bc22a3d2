"""The mutation catalogue (bench/verification/mutants.py): it matches the tree, covers what issue 11 asks for, and
a quick sample of it runs here, on a scratch copy, so a new blind spot fails the suite.  The whole catalogue:
``scripts/mutants`` (or ``tox -e mutants``)."""

import pytest

from bench.verification import mutants as mu


@pytest.mark.unit
def test_the_catalogue_matches_the_tree_and_covers_every_area():
    assert mu.check_catalogue() == []
    assert len(mu.CATALOGUE) >= 40
    areas = {m.area for m in mu.CATALOGUE}
    assert {"constants", "filters", "parity", "crc", "timing", "electrodes", "mechanics", "thermal", "adc",
            "noise"} <= areas
    assert set(mu.FAST) <= {m.name for m in mu.CATALOGUE}
    with pytest.raises(KeyError, match="unknown mutant"):
        mu.by_name(["no-such-mutant"])


@pytest.mark.unit
def test_the_readme_states_the_catalogues_size_and_names_are_unique():
    """README, Mutation catalogue: "holds N deliberate faults" is the catalogue's size (a count left stale after
    adding mutants is caught here), and no two mutants share a name (``--only NAME`` picks one)."""
    import re

    from bench.paths import REPO

    stated = re.findall(r"holds\s+(\d+) deliberate faults", (REPO / "README.md").read_text())
    assert stated == [str(len(mu.CATALOGUE))]
    names = [m.name for m in mu.CATALOGUE]
    assert len(set(names)) == len(names)


@pytest.mark.unit
def test_the_catalogue_check_names_a_test_that_no_longer_exists():
    import dataclasses

    m = next(m for m in mu.CATALOGUE if "::" in m.tests[0])
    renamed = dataclasses.replace(m, tests=(m.tests[0].split("::")[0] + "::test_renamed_since",))
    assert mu.check_catalogue(mutants=[renamed]) == [f"{m.name}: no test test_renamed_since in "
                                                     f"{m.tests[0].split('::')[0]}"]


@pytest.mark.mutants
def test_a_quick_sample_of_the_catalogue_is_caught_on_a_scratch_copy():
    """The sample (Boltzmann's constant, the second byte's parity on the host, the multiplexer's memory, the TDC
    bandwidth) must be caught; and a mutant run against a test that cannot see it must be reported as survived,
    so "caught" means something (the harness imports the scratch copy's modules, not the checkout's)."""
    blind = mu.Mutant("boltzmann-vs-parity-test", "constants", "emulator/params.py",
                      "BOLTZMANN_J_PER_K = 1.380649e-23", "BOLTZMANN_J_PER_K = 1.380649e-22",
                      ("emulator/tests/test_protocol.py::test_every_sampling_command_has_odd_parity",),
                      "a constant no parity test can see")
    results = {r.name: r for r in mu.run_catalogue(mu.by_name(mu.FAST) + [blind])}
    assert {n: results[n].status for n in mu.FAST} == {n: "caught" for n in mu.FAST}, \
        {n: results[n].detail for n in mu.FAST}
    assert results[blind.name].status == "survived"


def test_a_mutant_in_one_module_reaches_the_compiled_code_of_the_modules_that_import_it():
    """Numba caches a compiled function by its own file and freezes the globals it reads: a mutant of the SPI
    model's timing constants must invalidate the fast path's cache (it reads them), one of the friction step the
    sliding module's, and a data file none."""
    root = mu.REPO

    def names(rel):
        return {str(p.relative_to(root)) for p in mu.compiled_dependents(root, rel)}

    assert "emulator/spi/fastpath.py" in names("emulator/spi/model.py")
    assert "emulator/sliding.py" in names("emulator/friction.py")
    assert names("fixtures/textures/library.toml") == set()
    assert "emulator/spi/model.py" not in names("emulator/spi/model.py")
