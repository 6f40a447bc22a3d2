"""Building the bench's C parts (bench/hosts/native.py): folders named after the inputs' contents, one build per
output, the compiler's errors (warnings included) named, nothing half-written left, a temporary name per thread."""

import threading
from pathlib import Path

import pytest

from bench.errors import BuildError
from bench.hosts import native

pytestmark = pytest.mark.unit

GOOD = "int main(void) { return 0; }\n"


def test_a_build_folder_is_named_after_its_inputs_contents_in_order(tmp_path):
    """The same contents under other names share a folder; an edit to any input, or another order, gets a new one."""
    a, b, a_copy = tmp_path / "a.c", tmp_path / "b.c", tmp_path / "elsewhere.c"
    a.write_text(GOOD)
    b.write_text("int f(void) { return 1; }\n")
    a_copy.write_text(GOOD)
    root = tmp_path / "out"
    first = native.build_folder(root, [a, b])
    assert first.parent == root and native.build_folder(root, [a_copy, b]) == first
    assert native.build_folder(root, [b, a]) != first
    b.write_text("int f(void) { return 2; }\n")
    assert native.build_folder(root, [a, b]) != first


def test_compile_c_builds_an_output_once_and_names_the_compilers_complaint(tmp_path):
    """A program builds; asked again for the same output it is left as it is (its folder names its inputs); a source
    with a warning (an unused variable: -Werror) or an error is refused naming the file and line, leaving neither
    the output nor a temporary file."""
    source = tmp_path / "ok.c"
    source.write_text(GOOD)
    out = tmp_path / "build" / "ok"
    assert native.compile_c([source], out) == out and out.stat().st_size > 0
    before = out.stat().st_mtime_ns
    source.write_text("this is not C\n")
    assert native.compile_c([source], out) == out and out.stat().st_mtime_ns == before
    for name, text in (("warn.c", "int main(void) {\n  int unused = 0;\n  return 0;\n}\n"),
                       ("bad.c", "int main(void) {\n  return undeclared;\n}\n")):
        bad = tmp_path / name
        bad.write_text(text)
        with pytest.raises(BuildError, match=rf"the test program does not compile:\n(.|\n)*{name}:2"):
            native.compile_c([bad], tmp_path / "failed" / name, what="the test program")
    assert not list((tmp_path / "failed").iterdir())


def test_without_a_compiler_the_build_says_so(tmp_path, monkeypatch):
    source = tmp_path / "ok.c"
    source.write_text(GOOD)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    with pytest.raises(BuildError, match=r"^the library: no C compiler \('cc'\) on the PATH$"):
        native.compile_c([source], tmp_path / "out" / "lib", what="the library")


def test_builds_of_one_output_at_once_each_write_a_temporary_of_their_own(tmp_path, monkeypatch):
    """Two threads building the same output (a Dask worker's fault-campaign cases) compile into different temporary
    files, so neither moves the other's half-written file into place; both return the output."""
    names, both_started = [], threading.Barrier(2)

    def fake_cc(cmd, **kw):
        partial = Path(cmd[cmd.index("-o") + 1])
        names.append(partial.name)
        both_started.wait(timeout=10)
        partial.write_text("built")

        class Done:
            returncode, stderr = 0, ""
        return Done()

    monkeypatch.setattr(native.subprocess, "run", fake_cc)
    out = tmp_path / "lib.so"
    results = []
    threads = [threading.Thread(target=lambda: results.append(native.compile_c([tmp_path / "x.c"], out)))
               for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == [out, out] and len(set(names)) == 2 and out.read_text() == "built"


def test_a_compiler_failing_after_writing_part_of_its_output_leaves_nothing(tmp_path, monkeypatch):
    """cc removes its own output when it fails, but a compiler killed mid-write, or another toolchain, may not: the
    half-written temporary file is removed with the failure, and the output never appears."""
    def failing_cc(cmd, **kw):
        Path(cmd[cmd.index("-o") + 1]).write_text("half")

        class Failed:
            returncode, stderr = 1, "killed"
        return Failed()

    monkeypatch.setattr(native.subprocess, "run", failing_cc)
    with pytest.raises(BuildError, match="does not compile:\nkilled"):
        native.compile_c([tmp_path / "x.c"], tmp_path / "out" / "lib.so")
    assert not list((tmp_path / "out").iterdir())
