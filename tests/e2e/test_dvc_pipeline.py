"""`dvc repro` runs the same task as the command, and does nothing when nothing changed."""

import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from tests.conftest import BIN, REPO, run_cli


def _small_repo(tmp_path: Path) -> Path:
    """A git+DVC copy of the project's pipeline files with a small data config."""
    repo = tmp_path / "repo"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "cache", "tmp")
    for item in ("conf", "src", ".dvc", "dvc.yaml", ".dvcignore", "params.yaml"):
        src = REPO / item
        if src.is_dir():
            shutil.copytree(src, repo / item, ignore=ignore)
        else:
            repo.mkdir(exist_ok=True)
            shutil.copy2(src, repo / item)
    syn = repo / "conf/data/synthetic.yaml"
    cfg = yaml.safe_load(syn.read_text())
    cfg["synthetic"]["n_writers"] = 5
    cfg["augment"] = {"per_class": 2}
    syn.write_text(yaml.safe_dump(cfg))
    subprocess.run(["git", "init", "-q"], cwd=repo, check=True)
    return repo


def _dvc(repo: Path, *args: str) -> subprocess.CompletedProcess:
    env = {"PRG_CONF_DIR": str(repo / "conf"), "PATH": f"{BIN}:/usr/bin:/bin"}
    return run_cli("dvc", *args, cwd=repo, env=env)


def test_dvc_repro_prepare_equals_prg_prepare_and_is_idempotent(tmp_path):
    repo = _small_repo(tmp_path)
    first = _dvc(repo, "repro", "prepare")
    assert first.returncode == 0, first.stdout + first.stderr
    # core.autostage is off: dvc stages nothing in git, it says what to add
    staged = subprocess.run(
        ["git", "status", "--porcelain"], cwd=repo, capture_output=True, text=True
    )
    assert "dvc.lock" in staged.stdout
    assert not [line for line in staged.stdout.splitlines() if line[:1] not in (" ", "?")]
    assert "git add" in first.stdout and "dvc.lock" in first.stdout, first.stdout
    by_dvc = repo / "data/prepared/synthetic"

    direct_root = tmp_path / "direct"
    direct = run_cli(
        "prg-prepare",
        f"paths.root_dir={direct_root}",
        "progress=false",
        env={"PRG_CONF_DIR": str(repo / "conf")},
    )
    assert direct.returncode == 0, direct.stderr
    by_cli = direct_root / "data/prepared/synthetic"
    for name in ("train.npz", "val.npz", "test.npz", "manifest.json"):
        assert (by_dvc / name).read_bytes() == (by_cli / name).read_bytes(), name

    second = _dvc(repo, "repro", "prepare")
    assert second.returncode == 0
    assert "didn't change" in second.stdout or "up to date" in second.stdout, second.stdout
    metrics = _dvc(repo, "metrics", "show")
    assert "train_samples" in metrics.stdout

    # the same data built from another commit (a fresh clone's) differ only in the commit, which
    # is recorded in provenance.json, not in the manifest; DVC does not hash provenance.json, so
    # the dataset's lock entry does not move and nothing downstream reruns
    lock = (repo / "dvc.lock").read_text()
    assert "git_commit" not in (by_dvc / "manifest.json").read_text()
    provenance = by_dvc / "provenance.json"
    recorded = yaml.safe_load(provenance.read_text())
    recorded["code_version"]["git_commit"] = "f" * 40  # as built on another commit
    provenance.write_text(yaml.safe_dump(recorded))
    status = _dvc(repo, "status", "prepare")
    assert status.returncode == 0 and "up to date" in status.stdout, status.stdout
    again = _dvc(repo, "repro", "prepare")
    assert "didn't change" in again.stdout or "up to date" in again.stdout, again.stdout
    assert (repo / "dvc.lock").read_text() == lock

    # a DVC remote (a folder here; s3://, ssh://, ... alike) restores the outputs elsewhere
    # (provenance.json is a run fact of the build, neither hashed nor pushed)
    originals = {
        p.name: p.read_bytes()
        for p in by_dvc.iterdir()
        if p.is_file() and p.name != "provenance.json"
    }
    assert _dvc(repo, "remote", "add", "-d", "store", str(tmp_path / "remote")).returncode == 0
    pushed = _dvc(repo, "push")
    assert pushed.returncode == 0, pushed.stdout + pushed.stderr
    shutil.rmtree(repo / "data")
    shutil.rmtree(repo / ".dvc" / "cache")
    pulled = _dvc(repo, "pull", "prepare")
    assert pulled.returncode == 0, pulled.stdout + pulled.stderr
    assert {p.name: p.read_bytes() for p in by_dvc.iterdir() if p.is_file()} == originals
    assert "up to date" in _dvc(repo, "status", "prepare").stdout


@pytest.mark.slow  # four trainings and an evaluation through dvc: about 1 min of both cores
def test_dvc_plots_show_renders_the_training_curves_and_coherence_plots(tmp_path):
    """The pipeline's plots from real outputs: `dvc repro train` trains the four families in one
    multirun and writes each one's history.csv, `prg-evaluate` (coherence of one model) its
    reports/plots/, and `dvc plots show` renders them to HTML."""
    repo = _small_repo(tmp_path)
    trained = _dvc(repo, "repro", "train")
    assert trained.returncode == 0, trained.stdout[-3000:] + trained.stderr[-3000:]
    epochs = yaml.safe_load((repo / "conf/experiment/quick.yaml").read_text())["quick_epochs"]
    for family in ("cvae", "avae_ts", "avae_ti", "muse"):
        history = (repo / f"models/{family}/history.csv").read_text().splitlines()
        assert history[0].split(",")[:4] == ["epoch", "step", "train_loss", "val_loss"]
        assert len(history) == 1 + epochs[family], family  # one row per epoch of its budget
        assert (repo / f"models/{family}/model.ckpt").stat().st_size > 0
    # nothing changed: the stage is up to date and trains nothing
    again = _dvc(repo, "repro", "train")
    assert "didn't change" in again.stdout or "up to date" in again.stdout, again.stdout
    env = {"PRG_CONF_DIR": str(repo / "conf"), "PRG_ROOT": str(repo)}
    evaluated = run_cli(
        "prg-evaluate",
        "parts=[classifiers,coherence]",
        "families=[cvae]",
        "classifier.epochs=1",
        "figures=false",
        "progress=false",
        cwd=repo,
        env=env,
        timeout=600,
    )
    assert evaluated.returncode == 0, evaluated.stderr[-3000:]
    per_class = (repo / "reports/plots/coherence_per_class.csv").read_text().splitlines()
    assert per_class[0] == "class,cvae_T_from_S" and len(per_class) == 1 + 62
    shown = _dvc(repo, "plots", "show", "-o", "plots_html")
    assert shown.returncode == 0, shown.stdout + shown.stderr
    html = (repo / "plots_html" / "index.html").read_text()
    for plot in ("validation_loss", "coherence_per_class", "trajectory_coherence"):
        assert f"vegaEmbed('#{plot}" in html, plot  # the three plots dvc.yaml declares
    assert "val_loss" in html and "cvae_T_from_S" in html
