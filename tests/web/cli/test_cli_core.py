"""``s7graph run --core`` and ``CPU = {"core": …}`` (engine/cores.py): a program's blocks
run on the processor kept for the scan; a core that cannot be is refused in one line
naming where it was asked for, exit 2."""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

import pytest

from s7graph.web.cli import main


def _program(tmp_path: Path, core: object) -> Path:
    program = tmp_path / "prog.py"
    program.write_text(
        textwrap.dedent(f"""
        import os
        from s7graph.engine import ob
        CPU = {{"core": {core!r}}}

        @ob(1)
        def main(ctx):
            with open({str(tmp_path / "seen.txt")!r}, "w") as f:
                f.write(",".join(map(str, sorted(os.sched_getaffinity(0)))))
    """)
    )
    return program


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one processor: none to keep")
def test_a_programs_cpu_dict_keeps_a_processor_its_blocks_run_on(tmp_path: Path) -> None:
    core = max(os.sched_getaffinity(0))
    program = _program(tmp_path, core)
    state = str(tmp_path / "s.sqlite")
    assert main(["run", str(program), "--state", state, "--duration-s", "0.2"]) == 0
    assert (tmp_path / "seen.txt").read_text() == str(core)
    assert set(os.sched_getaffinity(0)) >= {core}  # the processors back afterwards


def test_a_programs_core_that_cannot_be_is_refused_naming_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    program = _program(tmp_path, "fast")
    assert main(["run", str(program), "--state", str(tmp_path / "s.sqlite")]) == 2
    assert capsys.readouterr().err == (
        f"s7graph: error: {program}: CPU option core: core 'fast' is none of auto, off or a "
        "processor number\n"
    )


def test_the_command_lines_core_overrides_the_programs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    program = _program(tmp_path, "fast")
    state = str(tmp_path / "s.sqlite")
    assert (
        main(["run", str(program), "--state", state, "--duration-s", "0.1", "--core", "off"]) == 0
    )
    assert (tmp_path / "seen.txt").exists()
    capsys.readouterr()
    assert main(["run", str(program), "--state", state, "--core", "4096"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("s7graph: error: --core: core 4096 is not a processor this process")
