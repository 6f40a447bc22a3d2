"""A built harness is reused only while it is built from the sources as they are now: the RTL, the C++ harness, the
property generator or the SP mask changed since its build makes :meth:`Harness.up_to_date` false, so
:meth:`Harness.ensure_built` builds it again (never a stale RTL under a run, README "over the RTL")."""

from __future__ import annotations

import shutil

from emulator.rtl import harness as H


def _as_built(harness: H.Harness) -> None:
    """Make ``harness``'s folder look built from the sources as they are (a binary and its sources' stamp)."""
    harness.build_dir.mkdir(parents=True, exist_ok=True)
    harness.binary.write_text("#!/bin/sh\n")
    (harness.build_dir / "sources.sha256").write_text(harness._sources_digest())


def test_a_harness_is_up_to_date_only_while_its_sources_and_mask_are_those_it_was_built_from(tmp_path, monkeypatch):
    harness = H.Harness(build_dir=tmp_path / "sp0")
    assert not harness.up_to_date()  # nothing built
    _as_built(harness)
    assert harness.up_to_date()
    own_cpp = tmp_path / "harness.cpp"  # a copy of the C++ harness, then one byte of it changed
    shutil.copy(H.HARNESS_CPP, own_cpp)
    monkeypatch.setattr(H, "HARNESS_CPP", own_cpp)
    assert harness.up_to_date()
    own_cpp.write_bytes(own_cpp.read_bytes() + b"\n")
    assert not harness.up_to_date()
    monkeypatch.undo()
    assert harness.up_to_date()
    own_rtl = [tmp_path / f"{k}_{p.name}" for k, p in enumerate(H.build.SOURCES)]  # the Verilog, one file changed
    for source, copy in zip(H.build.SOURCES, own_rtl):
        shutil.copy(source, copy)
    monkeypatch.setattr(H.build, "SOURCES", own_rtl)
    assert harness.up_to_date()
    own_rtl[-1].write_bytes(own_rtl[-1].read_bytes() + b"// changed\n")
    assert not harness.up_to_date()
    monkeypatch.undo()
    assert harness.up_to_date()
    other_mask = H.Harness(build_dir=tmp_path / "sp0", sp=1)  # the same folder and sources, another SP mask
    assert not other_mask.up_to_date()
    harness.binary.unlink()
    assert not harness.up_to_date()  # a stamp without its binary
