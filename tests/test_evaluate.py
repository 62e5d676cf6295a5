"""`prg-evaluate`: Table I, coherence and robustness reports from real (tiny) trained models,
written atomically, logged to a real SQLite MLflow store; bad input gets one line."""

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
import torch
from mlflow import MlflowClient

from prg.commands.cli import compose_config
from prg.commands.evaluate import dataset_dir, evaluate
from prg.commands.train import train
from prg.evaluation.classifiers import FOLD, load_classifier, predict
from prg.evaluation.coherence import coherence_cells, per_class_rate
from prg.evaluation.likelihood import MODEL_STD_SUFFIX, PAPER_TABLE1, TABLE1_CELLS, estimate_cell
from prg.evaluation.run import load_test_data, subset
from prg.evaluation.smoothness import median_roughness
from prg.models.checkpoint import load_model
from prg.models.components import shift_images
from prg.models.likelihoods import Likelihoods
from prg.tracking import sqlite_uri
from tests.conftest import run_cli

FAMILIES = ("cvae", "avae_ts", "avae_ti", "muse")
TINY = [
    "likelihood.k_marginal=4",
    "likelihood.k_conditional=6",
    "likelihood.n_test=12",
    "classifier.epochs=1",
    "kinematics.words=[ab]",
    "progress=false",
]


@pytest.fixture(scope="module")
def trained_root(tmp_path_factory, small_dataset) -> Path:
    """A project root whose models/<family>/model.ckpt hold briefly trained models."""
    root = tmp_path_factory.mktemp("root")
    for family in FAMILIES:
        cfg = compose_config(
            "train",
            [
                f"paths.root_dir={root}",
                f"paths.data_dir={small_dataset}",
                f"model={family}",
                "trainer.max_epochs=1",
                "trainer.limit_train_batches=2",
                "trainer.limit_val_batches=1",
                "trainer.enable_progress_bar=false",
                "callbacks.figures.every_n_epochs=100",
                f"export_dir={root}/models/{family}",
            ],
        )
        train(cfg)
    return root


def _cfg(root: Path, data_dir: Path, *overrides: str):
    return compose_config(
        "evaluate", [f"paths.root_dir={root}", f"paths.data_dir={data_dir}", *TINY, *overrides]
    )


def test_reports_tables_figures_and_mlflow(trained_root, small_dataset):
    cfg = _cfg(trained_root, small_dataset)
    result = evaluate(cfg)
    reports = trained_root / "reports"
    models = {f: load_model(trained_root / f"models/{f}/model.ckpt")[0] for f in FAMILIES}

    # kinematics: the word planned and executed with both timings, LASA and the two controls
    groups = [r["group"] for r in result.kinematics]
    assert groups[:4] == [
        "human: planned",
        "human: executed",
        "constant: planned",
        "constant: executed",
    ]
    assert {"LASA (human)", "control: white noise", "control: constant speed"} <= set(groups)
    assert "human: executed" in (reports / "kinematics.md").read_text()
    assert "kinematics/human_executed_beta" in result.metrics

    # Table I: each family fills exactly the cells it supports, which are the paper's cells,
    # and its trajectory-target cells once more under its own std
    cells = {(r["model"], r["cell"]) for r in result.table1}
    for family, model in models.items():
        mine = {c for m, c in cells if m == family and not c.endswith(MODEL_STD_SUFFIX)}
        assert mine == {c for c, cell in TABLE1_CELLS.items() if cell in model.likelihood_cells}
        assert mine == set(PAPER_TABLE1[family])
        own = {c for m, c in cells if m == family and c.endswith(MODEL_STD_SUFFIX)}
        assert own == {c + MODEL_STD_SUFFIX for c in mine if TABLE1_CELLS[c][0] == "traj"}
    assert all(math.isfinite(r["value"]) and r["n_test"] == 12 for r in result.table1)
    assert {r["k"] for r in result.table1 if "_given_" in r["cell"]} == {6}
    with open(reports / "table1.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(result.table1)
    assert float(rows[0]["value"]) == pytest.approx(result.table1[0]["value"], rel=1e-5)
    table = (reports / "table1.md").read_text()
    assert "(-192.75)" in table and "PRG_MUSE(T,S,I)" in table and "Density convention" in table
    assert "## Trajectory cells under each model's own std" in table
    assert {r["traj_std"] for r in result.table1 if r["cell"] == "logp_T"} == {1.0}
    assert {r["traj_std"] for r in result.table1 if r["cell"] == "logp_T_model_std"} == {0.1}
    assert {r["traj_std"] for r in result.table1 if r["cell"] == "logp_S"} == {None}

    # the one-pass pair equals two separate estimates with the same seed: the default table
    # under a unit-variance Gaussian, the second under the model's own std
    data = subset(load_test_data(dataset_dir(cfg)), 12, cfg.seed)
    by_key = {(r["model"], r["cell"]): r["value"] for r in result.table1}
    for family, cell in (("muse", "logp_T_given_S"), ("avae_ti", "logp_T")):
        target, given = TABLE1_CELLS[cell]
        k = 6 if given else 4
        model = models[family]
        for key, lik in ((cell, Likelihoods(1.0)), (cell + MODEL_STD_SUFFIX, model.likelihoods)):
            alone = estimate_cell(model, target, given, data, k, 64, 4096, cfg.seed, False, lik)
            assert by_key[(family, key)] == pytest.approx(alone.mean().item(), abs=1e-3)

    # coherence: every subset x target x kind; MUSE has 7 subsets and 3 targets, and the
    # imputed kind beside the mean and sampled ones (only it imputes)
    muse = [r for r in result.coherence if r["model"] == "muse"]
    assert len(muse) == 7 * 3 * 3
    assert {r["model"] for r in result.coherence if r["kind"] == "imputed"} == {"muse"}
    assert all(0.0 <= r["coherence"] <= r["coherence_folded"] <= 1.0 for r in result.coherence)
    with open(reports / "coherence.csv") as f:
        coherence_csv = list(csv.DictReader(f))
    assert [float(r["coherence_folded"]) for r in coherence_csv] == pytest.approx(
        [r["coherence_folded"] for r in result.coherence], abs=1e-5
    )
    cvae = {(r["target"], r["given"]) for r in result.coherence if r["model"] == "cvae"}
    assert cvae == {("traj", "S"), ("traj", "T,S")}
    robustness = (reports / "robustness.md").read_text()
    assert "{S,I}" in robustness and "{T,S,I}*" in robustness
    assert "# Missing-modality robustness" in robustness

    # images moved off-centre: the models that take an image alone, each cross-modal target,
    # unmoved and at each configured shift; the unmoved rows agree with the coherence cells
    shifted = {(r["model"], r["target"], r["shift"]) for r in result.shifted_images}
    shifts = (0, *cfg.coherence.image_shifts)
    assert shifted == {("avae_ti", "traj", s) for s in shifts} | {
        ("muse", t, s) for t in ("traj", "label") for s in shifts
    }
    mean = {
        (r["model"], r["target"], r["given"]): r for r in result.coherence if r["kind"] == "mean"
    }
    for row in result.shifted_images:
        if row["shift"] == 0:
            same = mean[(row["model"], row["target"], "I")]
            assert row["coherence_folded"] == pytest.approx(same["coherence_folded"], abs=1e-6)
    assert "## Images moved off-centre" in robustness and "moved <= 2 px" in robustness
    coherence_md = (reports / "coherence.md").read_text()
    assert "test accuracy" in coherence_md and "mean, folded" in coherence_md
    assert "## Smoothness of decoded letters" in coherence_md
    figures = {p.name for p in (reports / "figures").iterdir()}
    assert {"muse_T_given_S.png", "muse_I_given_T.png", "muse_coherence_per_class.png"} <= figures

    # metrics.json and MLflow: test metrics in each model's training run, reports as artifacts
    metrics = json.loads((reports / "metrics.json").read_text())
    assert metrics == result.metrics

    # folded coherence beside every exact value, and recomputed for one cell: the letters MUSE
    # decodes from labels, classified, a prediction in the label's shape-twin group counted right
    exact = {k for k in metrics if "/coherence_" in k and "/coherence_folded_" not in k}
    folded = {k for k in metrics if "/coherence_folded_" in k}
    assert folded == {k.replace("/coherence_", "/coherence_folded_", 1) for k in exact}
    test = load_test_data(dataset_dir(cfg))
    labels = test["label"].numpy()
    muse_s = models["muse"].generate({"label": test["label"]}, "traj")[0]
    classifier, _ = load_classifier(trained_root / "models/classifiers/traj.pt")
    predicted = predict(classifier, muse_s).numpy()
    assert metrics["muse/coherence_T_given_S"] == pytest.approx(
        np.mean(predicted == labels), abs=1e-3
    )
    assert metrics["muse/coherence_folded_T_given_S"] == pytest.approx(
        np.mean(FOLD[predicted] == FOLD[labels]), abs=1e-3
    )
    steps = cfg.coherence.impute_steps
    muse_s_imputed = models["muse"].generate({"label": test["label"]}, "traj", impute_steps=steps)[
        0
    ]
    imputed = predict(classifier, muse_s_imputed).numpy()
    assert metrics["muse/coherence_folded_imputed_T_given_S"] == pytest.approx(
        np.mean(FOLD[imputed] == FOLD[labels]), abs=1e-3
    )

    # roughness of decoded letters over the test letters' (posterior mean, whole test split)
    reference = median_roughness(test["traj"].numpy())
    assert metrics["test_split/roughness"] == pytest.approx(reference, abs=1e-4)
    assert metrics["muse/roughness_ratio_T_given_S"] == pytest.approx(
        median_roughness(muse_s.numpy()) / reference, rel=1e-3
    )
    ti_i = models["avae_ti"].generate({"image": test["image"]}, "traj")[0]
    assert metrics["avae_ti/roughness_ratio_T_given_I"] == pytest.approx(
        median_roughness(ti_i.numpy()) / reference, rel=1e-3
    )
    # the label MUSE reads from test images moved by up to 2 pixels, recomputed by hand
    torch.manual_seed(cfg.seed)  # generate() draws from the global generator
    generator = torch.Generator().manual_seed(cfg.seed)
    moved = shift_images(test["image"], 2, generator)
    read = models["muse"].generate({"image": moved}, "label")[0].argmax(-1).numpy()
    assert metrics["muse/coherence_S_given_I_shift2"] == pytest.approx(
        np.mean(read == labels), abs=1e-3
    )
    ratio_keys = {k for k in metrics if "/roughness_ratio_" in k}
    assert ratio_keys == {
        "cvae/roughness_ratio_T_given_S",
        "avae_ts/roughness_ratio_T_given_S",
        "avae_ti/roughness_ratio_T_given_I",
        "muse/roughness_ratio_T_given_S",
        "muse/roughness_ratio_T_given_I",
        "muse/roughness_ratio_imputed_T_given_S",
        "muse/roughness_ratio_imputed_T_given_I",
    }
    assert metrics["muse/roughness_ratio_imputed_T_given_S"] == pytest.approx(
        median_roughness(muse_s_imputed.numpy()) / reference, rel=1e-3
    )
    client = MlflowClient(sqlite_uri(trained_root / "mlruns.db"))
    run_id = json.loads((trained_root / "models/muse/metrics.json").read_text())["mlflow_run_id"]
    logged = client.get_run(run_id).data.metrics
    assert logged["test/logp_T_given_S"] == pytest.approx(metrics["muse/logp_T_given_S"])
    assert logged["test/coherence_T_given_S"] == pytest.approx(metrics["muse/coherence_T_given_S"])
    experiment = client.get_experiment_by_name("prg-tasks").experiment_id  # task runs apart
    (run,) = client.search_runs([experiment], "tags.`prg.task` = 'evaluate'")
    artifacts = {a.path for a in client.list_artifacts(run.info.run_id, "reports")}
    assert {"reports/table1.md", "reports/coherence.csv", "reports/robustness.md"} <= artifacts
    assert not [p for p in reports.iterdir() if p.name.startswith(".evaluate")]


def test_estimates_are_deterministic_for_a_seed(trained_root, small_dataset):
    model, _ = load_model(trained_root / "models/muse/model.ckpt")
    g = torch.Generator().manual_seed(0)
    data = {
        "traj": torch.randn(5, 200, generator=g) * 0.3,
        "label": torch.randint(0, 62, (5,), generator=g),
        "image": torch.rand(5, 1, 28, 28, generator=g),
    }
    a = estimate_cell(model, "image", ("traj",), data, k=7, batch_size=2, chunk_rows=6, seed=3)
    b = estimate_cell(model, "image", ("traj",), data, k=7, batch_size=2, chunk_rows=6, seed=3)
    c = estimate_cell(model, "image", ("traj",), data, k=7, batch_size=2, chunk_rows=6, seed=4)
    assert torch.equal(a, b)
    assert not torch.equal(a, c)


def test_coherence_cells_follow_what_each_family_accepts(trained_root):
    for family in FAMILIES:
        model, _ = load_model(trained_root / f"models/{family}/model.ckpt")
        cells = coherence_cells(model)
        assert {given for _, given in cells} == set(model.accepted_inputs)
        assert {target for target, _ in cells} == set(model.generated_modalities)


def test_per_class_rate_matches_a_direct_count():
    rng = np.random.default_rng(0)
    labels = rng.integers(0, 5, 200)
    correct = rng.random(200) < 0.3
    rates = per_class_rate(torch.from_numpy(correct), torch.from_numpy(labels), 7).numpy()
    for c in range(5):
        assert rates[c] == pytest.approx(correct[labels == c].mean())
    assert np.isnan(rates[5:]).all()


def test_classifiers_part_alone(tmp_path, small_dataset):
    result = run_cli(
        "prg-evaluate",
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        "parts=[classifiers]",
        *TINY,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    folder = tmp_path / "models/classifiers"
    assert {"traj.pt", "image.pt", "metrics.json"} <= {p.name for p in folder.iterdir()}
    assert not (tmp_path / "reports").exists()


BAD = [
    (["models_dir={root}/nowhere"], "does not exist"),
    (["+checkpoints.muse={root}/models/cvae/model.ckpt"], "holds a cvae model, not muse"),
    (["+checkpoints.a={root}/models/muse/metrics.json"], "not a readable checkpoint"),
    (["likelihood.k_marginal=0"], "likelihood.k_marginal must be an integer in [1, "),
    (["likelihood.k_conditional=many"], "likelihood.k_conditional must be an integer in [1, "),
    (["families=[cvae]", "likelihood.cells=[logp_I]"], "cvae cannot estimate log p(x_I)"),
    (["likelihood.cells=[logp_X]"], "likelihood.cells"),
    (["parts=[plots]"], "parts"),
    (["coherence.temperatures.mean=-1"], "temperatures.mean"),
    (["coherence.image_shifts=[1,-2]"], "coherence.image_shifts[1] must be an integer in [0, 8]"),
    (["likelihood.traj_std=0"], "likelihood.traj_std must be a finite number in (0, 100] or null"),
]


@pytest.mark.parametrize("args, expected", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_gets_one_line_and_exit_2_and_writes_nothing(
    tmp_path, trained_root, small_dataset, args, expected
):
    reports = tmp_path / "reports"
    result = run_cli(
        "prg-evaluate",
        f"paths.root_dir={trained_root}",
        f"paths.data_dir={small_dataset}",
        f"report_dir={reports}",
        *TINY,
        *[a.format(root=trained_root) for a in args],
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith("prg-evaluate: error:"), lines
    assert expected in lines[0]
    assert not reports.exists()


SETTINGS_REFUSED = [
    (
        ["parts=[plots]"],
        "parts ['plots']: choose from ['classifiers', 'likelihood', 'coherence', 'likeness', "
        "'styles', 'kinematics']",
    ),
    (
        ["parts=[]"],
        "parts []: choose from ['classifiers', 'likelihood', 'coherence', 'likeness', 'styles', "
        "'kinematics']",
    ),
    (
        ["likelihood.cells=[logp_X,logp_T]"],
        "likelihood.cells ['logp_X']: use 'all' or a list of ['logp_T', 'logp_S', 'logp_I', "
        "'logp_T_given_S', 'logp_T_given_I', 'logp_S_given_T', 'logp_I_given_T']",
    ),
    (
        ["+coherence.temperatures.imputed=0"],
        "coherence.temperatures: 'imputed' names the imputed kind; rename it",
    ),
]


@pytest.mark.parametrize(
    "args, expected", SETTINGS_REFUSED, ids=[a[0] for a, _ in SETTINGS_REFUSED]
)
def test_settings_refuse_a_value_naming_its_config_path(tmp_path, args, expected):
    from prg.commands.evaluate import evaluation_settings
    from prg.errors import UsageError

    with pytest.raises(UsageError) as err:
        evaluation_settings(_cfg(tmp_path, tmp_path, *args))
    assert str(err.value) == expected


def test_settings_of_the_shipped_config_and_of_the_library_alone():
    from prg.commands.evaluate import evaluation_settings
    from prg.errors import SettingsError
    from prg.evaluation.settings import CoherenceSettings, EvaluationSettings, LikelihoodSettings

    settings = evaluation_settings(compose_config("evaluate", ["likelihood.cells=logp_T"]))
    assert settings.parts == ("likelihood", "coherence", "likeness", "styles", "kinematics")
    assert not settings.classifiers_only
    assert settings.likelihood.requested == (["logp_T"], True)
    assert settings.coherence.temperatures == {"mean": 0.0, "sampled": 1.0}
    assert settings.coherence.impute_steps == 20
    assert (settings.classifier.epochs, settings.classifier.lr) == (4, 0.002)
    assert EvaluationSettings().likelihood.requested == (list(TABLE1_CELLS), False)
    # the library names the field; the command layer adds the node's path
    with pytest.raises(SettingsError, match=r"^k_marginal must be an integer in \[1, "):
        LikelihoodSettings(k_marginal=0)
    assert settings.coherence.image_shifts == (1, 2) == CoherenceSettings().image_shifts
    with pytest.raises(SettingsError, match=r"^image_shifts\[0\] must be an integer in \[0, 8\]"):
        CoherenceSettings(image_shifts=[9])
    with pytest.raises(SettingsError, match=r"^temperatures\.mean must be a finite number"):
        CoherenceSettings(temperatures={"mean": float("nan")})
    with pytest.raises(SettingsError, match=r"^n_test must be an integer >= 1 or null"):
        EvaluationSettings(n_test=0)
