"""studies.analysis statistics: each function against the scipy/statsmodels call it names, and the
paper's numbers (shared/reference/studies.md) reproduced from the paper's summaries."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd

from tests.helpers.study_analysis_validate import REPO


def test_a_study_where_almost_every_word_was_spotted_by_everyone_analyses(tmp_path):
    """Simulated at a 0.999 rate, 9 of 10 words reach 100 %: the report is written, exit 0
    (the per-word figure used to fail on a negative error bar)."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    study = str(root / "conf/study/turing.yaml")
    responses = tmp_path / "turing.csv"

    def run(*args: str) -> subprocess.CompletedProcess:
        code = "import sys; from studies.cli import main; sys.exit(main())"
        return subprocess.run(
            [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300
        )

    made = run(
        "simulate",
        "turing",
        "--participants",
        "20",
        "--true-rate",
        "0.999",
        "--icc",
        "0",
        "--seed",
        "1",
        "--study",
        study,
        "--out",
        str(responses),
    )
    assert made.returncode == 0, made.stderr
    rates = pd.read_csv(responses).groupby("word")["chose_robot"].mean()
    assert (rates == 1.0).sum() >= 5  # boundary words are really there
    result = run("analyze", str(responses), "--study", study, "--out", str(tmp_path / "report"))
    assert result.returncode == 0, result.stderr[-2000:]
    assert (tmp_path / "report" / "report.html").is_file()


REPO = Path(__file__).resolve().parents[2]


def test_module_runner_gives_one_line_errors_and_exit_codes(tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "studies.analysis.commands", "analyze", str(tmp_path / "none.csv")],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2
    assert (
        run.stderr
        == f"prg-study: error: {tmp_path / 'none.csv'}: no such responses file (expected a long-format CSV)\n"
    )


def test_schema_imports_without_pandas_or_numpy():
    code = "import sys, studies.analysis.schema; sys.exit(any(m in sys.modules for m in ('pandas', 'numpy')))"
    assert subprocess.run([sys.executable, "-c", code], cwd=REPO).returncode == 0
