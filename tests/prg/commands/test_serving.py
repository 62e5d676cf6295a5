"""Tests of ``prg.commands.serving`` (moved from the suite on: trained models as MLflow models
(prg.serving): logged by every training run, loaded with ``mlflow.pyfunc.load_model``,
registered with metrics and a champion alias, and served over HTTP by the real ``mlflow models
serve`` on loopback)."""

from __future__ import annotations

from prg.commands.serving import main


def test_register_refuses_a_folder_that_is_no_export_in_one_line(tmp_path, capsys):
    (tmp_path / "metrics.json").write_text("{}")
    assert (
        main(["register", str(tmp_path), "--tracking-uri", "sqlite:///" + str(tmp_path / "x.db")])
        == 2
    )
    (line,) = capsys.readouterr().out.strip().splitlines()
    assert "expected the family and mlflow_run_id of a prg-train export" in line


def test_a_missing_argument_is_one_line_and_exit_2(capsys):
    assert main(["register"]) == 2
    (line,) = capsys.readouterr().out.strip().splitlines()
    assert "export_dir" in line
