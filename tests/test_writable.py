"""An output path the file system refuses is one line naming it and the reason, before the
command runs (output/writable.py), for every command that writes."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.output.writable import refusal

HOLD = str(PROBLEMS / "holding_m45.toml")


def _place(folder: Path, suffix: str = "") -> dict[str, Path]:
    """Refused outputs (names ending in ``suffix``) of each kind under ``folder``: a parent
    that is a file, a name of 300 bytes, a dangling symbolic link, a loop of them, a path
    through the loop."""
    (folder / "afile").write_text("")
    (folder / f"dangling{suffix}").symlink_to(f"nowhere{suffix}")
    for loop in {"loop", f"loop{suffix}"}:
        (folder / loop).symlink_to(loop)
    return {
        "is a file, not a folder": folder / "afile" / f"out{suffix}",
        "a name of 300 bytes: the file system takes at most 255": folder
        / ("x" * (300 - len(suffix)) + suffix),
        f"is a symbolic link to nowhere{suffix}, which does not exist": folder
        / f"dangling{suffix}",
        "is a loop of symbolic links": folder / f"loop{suffix}",
        "loop is a loop of symbolic links": folder / "loop" / f"out{suffix}",
    }


@pytest.mark.parametrize("folder", [True, False])
def test_each_refusal_names_its_reason(tmp_path: Path, folder: bool) -> None:
    for reason, path in _place(tmp_path).items():
        assert reason in (refusal(path, folder=folder) or ""), path
    assert refusal(tmp_path / "new" / "deeper", folder=folder) is None
    assert refusal(tmp_path, folder=True) is None
    assert "is a folder, not a file" in (refusal(tmp_path, folder=False) or "")
    assert "is a file, not a folder" in (refusal(tmp_path / "afile", folder=True) or "")


def test_the_check_leaves_nothing_behind(tmp_path: Path) -> None:
    assert refusal(tmp_path / "out") is None
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="no /proc")
def test_proc_refuses_new_files() -> None:
    assert "/proc refuses new files" in (refusal(Path("/proc")) or "")
    assert "/proc refuses new files" in (refusal(Path("/proc/out")) or "")


def test_a_folder_we_may_not_write(tmp_path: Path) -> None:
    """A read-only folder: refused when the file system refuses it (as root it does not:
    root writes into a folder of mode 0o555, and the check asks the file system itself)."""
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    try:
        with contextlib.suppress(OSError):
            (locked / "probe").mkdir()
        writable = (locked / "probe").is_dir()
        with contextlib.suppress(OSError):
            (locked / "probe").rmdir()
        reason = refusal(locked / "out")
        assert (reason is None) == writable
        if not writable:
            assert "locked refuses new files: Permission denied" in reason
    finally:
        locked.chmod(0o755)


#: Every command that writes, with the arguments that name its output (OUT).
WRITERS = {
    "simulate": ["simulate", HOLD, "--duration", "10", "--no-figures", "--out", "OUT"],
    "solve": ["solve", HOLD, "--out", "OUT"],
    "whatif": ["whatif", HOLD, "--static", "--vary", "loads[0].mass_kg=1,2", "--out", "OUT"],
    "batch": ["batch", HOLD, "--quiet", "--out", "OUT"],
    "population": ["population", HOLD, "--n", "1", "--out", "OUT"],
    "duty-cycle": ["duty-cycle", HOLD, "--t-off", "30", "--out", "OUT"],
    "sensitivity": ["sensitivity", HOLD, "--out", "OUT"],
    "design": [
        "design",
        str(PROBLEMS / "holding_horizontal.toml"),
        "--free",
        "tasks[0].point_m[2],tasks[1].target_m[2]=-0.5:0.1",
        "--out",
        "OUT",
    ],
    "compare": ["compare", HOLD, "--out", "OUT"],
    "curve": ["curve", HOLD, "--dof", "elbow_flexion", "--out", "OUT"],
    "init": ["init", "hold", "OUT"],
}


@pytest.mark.parametrize("command", sorted(WRITERS))
def test_every_writing_command_refuses_before_it_runs(tmp_path: Path, command: str) -> None:
    suffix = {"curve": ".png", "init": ".toml"}.get(command, "")
    for reason, path in _place(tmp_path, suffix).items():
        args = [a.replace("OUT", str(path)) for a in WRITERS[command]]
        result = CliRunner().invoke(main, [*args, "--force"])
        lines = result.stderr.strip().splitlines()
        assert result.exit_code == 2, (command, path, result.output)
        assert len(lines) == 1 and lines[0].endswith(f"{reason})"), lines
        assert lines[0].startswith(f"error: {'FILE' if command == 'init' else '--out'} = ")
    assert not (tmp_path / f"nowhere{suffix}").exists()  # nothing written through the link


def test_evaluate_refuses_a_file_where_the_prediction_goes(tmp_path: Path) -> None:
    run = tmp_path / "run"
    quick = ["--duration", "5", "--no-figures", "--no-report"]
    done = CliRunner().invoke(main, ["simulate", HOLD, *quick, "--out", str(run)])
    assert done.exit_code == 0, done.output
    out = tmp_path / "evaluation"
    out.mkdir()
    (out / "predicted").write_text("a note of the user's\n")
    motion = ["--motion", str(run / "timeline.csv"), "--out", str(out), "--force"]
    result = CliRunner().invoke(main, ["evaluate", HOLD, *motion, "--compare-prediction"])
    assert result.exit_code == 2, result.output
    line = result.stderr.strip()
    assert line.startswith("error: --out = ")
    assert line.endswith(
        f": expected a folder the file system can write ({out / 'predicted'} is a file, "
        "not a folder)"
    )
    assert (out / "predicted").read_text() == "a note of the user's\n"
    assert os.listdir(out) == ["predicted"]  # refused before anything ran
