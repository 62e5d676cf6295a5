"""Commands from anywhere: the project root comes from ``PRG_ROOT``, else the nearest project
folder above the working folder, else the code's checkout, else ``~/.local/share/prg``; every
default output (outputs, logs, Hydra's run folder, the MLflow store) goes under it and nothing
into the working folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from prg.commands import cli
from prg.commands.cli import compose_config, is_project_root, project_root
from tests.conftest import REPO, run_cli, wait_for_pending_runs

PYPROJECT = '[build-system]\nrequires = ["setuptools"]\n\n[project]\nname = "prg"\nversion = "0"\n'


def make_project(folder: Path, pyproject: str = PYPROJECT) -> Path:
    """A folder with the project's marker: dvc.yaml next to a pyproject.toml named prg."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "dvc.yaml").write_text("stages: {}\n")
    (folder / "pyproject.toml").write_text(pyproject)
    return folder


def files_under(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


@pytest.fixture
def no_root_env(monkeypatch):
    monkeypatch.delenv("PRG_ROOT", raising=False)


def test_the_marker_is_dvc_yaml_next_to_the_pyproject_of_prg(tmp_path):
    assert is_project_root(REPO)
    assert is_project_root(make_project(tmp_path / "ok"))
    only_dvc = tmp_path / "only-dvc"
    only_dvc.mkdir()
    (only_dvc / "dvc.yaml").write_text("stages: {}\n")
    assert not is_project_root(only_dvc)
    assert not is_project_root(make_project(tmp_path / "other", PYPROJECT.replace("prg", "prgx")))
    named_elsewhere = '[project]\nname = "other"\n\n[tool.x]\nname = "prg"\n'
    assert not is_project_root(make_project(tmp_path / "tool", named_elsewhere))
    no_dvc = make_project(tmp_path / "no-dvc")
    (no_dvc / "dvc.yaml").unlink()
    assert not is_project_root(no_dvc)


def test_the_root_is_found_from_the_working_folder_upward(tmp_path, monkeypatch, no_root_env):
    project = make_project(tmp_path / "project")
    deep = project / "a" / "b"
    deep.mkdir(parents=True)
    monkeypatch.chdir(deep)
    assert project_root() == (project, "found above the working folder")
    cfg = compose_config("write", [], hydra_config=True)
    assert cfg.paths.root_dir == str(project)
    assert cfg.out_dir.startswith(f"{project}/outputs/")
    assert cfg.hydra.run.dir.startswith(f"{project}/logs/write/runs/")  # Hydra's own folder too
    assert cfg.logger.artifact_location == f"{project}/mlartifacts"


def test_prg_root_wins_and_is_made_absolute(tmp_path, monkeypatch):
    monkeypatch.chdir(make_project(tmp_path / "project"))
    monkeypatch.setenv("PRG_ROOT", "elsewhere")
    assert project_root() == (tmp_path / "project" / "elsewhere", "PRG_ROOT")
    cfg = compose_config("prepare", [])
    assert cfg.paths.data_dir == f"{tmp_path}/project/elsewhere/data"


def test_without_a_project_the_code_checkout_then_the_user_data_folder(
    tmp_path, monkeypatch, no_root_env
):
    monkeypatch.chdir(tmp_path)
    root, origin = project_root()
    assert root == REPO and "checkout" in origin  # the tests run from a checkout of the code
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data-home"))
    monkeypatch.setattr(cli, "is_project_root", lambda folder: False)  # as an installed wheel
    default = tmp_path / "data-home" / "prg"
    assert project_root() == (default, "the default, no project above the working folder")
    assert compose_config("write", []).paths.root_dir == str(default)


def test_prg_root_is_honoured_by_a_real_command_and_nothing_lands_in_the_working_folder(
    tmp_path,
):
    """A missing model: the line names the absolute path looked at and how to point elsewhere;
    Hydra's run folder is under PRG_ROOT, the working folder (inside another project) stays
    empty."""
    cwd = make_project(tmp_path / "project") / "sub"
    cwd.mkdir()
    root = tmp_path / "root"
    result = run_cli("prg-write", "text=hi", cwd=cwd, env={"PRG_ROOT": str(root)})
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-2000:]
    expected = f"checkpoint {root}/models/muse/model.ckpt does not exist"
    assert lines[0].startswith(f"prg-write: error: {expected}"), lines[0]
    assert f"project root {root}: PRG_ROOT" in lines[0]
    assert "ckpt=FILE" in lines[0] and "PRG_ROOT=FOLDER" in lines[0]
    assert files_under(cwd) == set()
    assert files_under(tmp_path / "project") == {"dvc.yaml", "pyproject.toml", "sub"}
    assert any(root.glob("logs/write/runs/*/.hydra/config.yaml"))


def test_a_command_run_below_a_project_writes_every_output_under_it(
    tmp_path, untrained_muse_checkpoint
):
    project = make_project(tmp_path / "project")
    (project / "models" / "muse").mkdir(parents=True)
    os.symlink(untrained_muse_checkpoint, project / "models" / "muse" / "model.ckpt")
    cwd = project / "notes"
    cwd.mkdir()
    env = {"PRG_ROOT": ""}  # set but empty: not given
    result = run_cli("prg-write", "text=hi", "record=false", cwd=cwd, env=env)
    assert result.returncode == 0, result.stderr[-2000:]
    assert files_under(cwd) == set()
    words = list(project.glob("outputs/write/muse/*/word.json"))
    assert len(words) == 1
    wait_for_pending_runs(project)  # the run is logged by a background process
    assert (project / "mlruns.db").is_file() and (project / "mlartifacts").is_dir()
    assert any(project.glob("logs/write/runs/*/.hydra/config.yaml"))
