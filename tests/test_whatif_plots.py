"""What-if figures show any varied value, however long, in a label that fits."""

from __future__ import annotations

import warnings
from pathlib import Path

from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.runs.whatif_plots import SHOWN_CHARACTERS, _short


def test_a_long_value_is_cut_on_the_figures_and_they_lay_out(tmp_path: Path) -> None:
    assert _short("T" * 5000) == "T" * (SHOWN_CHARACTERS - 1) + "…"
    assert _short("short") == "short"
    title = "T" * 5000
    args = ["whatif", str(PROBLEMS / "holding_m45.toml"), "--static", "--quiet", "--no-report"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = CliRunner().invoke(
            main, [*args, "--vary", f"title={title},short", "--out", str(tmp_path / "w")]
        )
    assert result.exit_code == 0, result.output
    assert [str(w.message) for w in caught if "layout" in str(w.message)] == []
    assert len(list((tmp_path / "w").glob("whatif_*_vs_title.png"))) == 4
