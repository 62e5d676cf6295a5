"""Tests of ``prg.evaluation.likelihood`` (moved from the suite on: `prg-evaluate`: Table I,
coherence and robustness reports from real (tiny) trained models, written atomically, logged to
a real SQLite MLflow store; bad input gets one line)."""

import csv
import json
import math

import numpy as np
import pytest
import torch
from mlflow import MlflowClient

from prg.commands.evaluate import dataset_dir, evaluate
from prg.errors import UsageError
from prg.evaluation.classifiers import FOLD, load_classifier, predict
from prg.evaluation.likelihood import (
    MODEL_STD_SUFFIX,
    PAPER_TABLE1,
    TABLE1_CELLS,
    estimate_cell,
    iw_log_likelihood,
    iw_log_likelihoods,
)
from prg.evaluation.run import load_test_data, subset
from prg.evaluation.smoothness import median_roughness
from prg.models.base import Gaussian, ImportancePath
from prg.models.checkpoint import load_model
from prg.models.components import shift_images
from prg.models.likelihoods import Likelihoods
from prg.tracking import sqlite_uri
from tests.helpers.evaluate import FAMILIES, _cfg, trained_root  # noqa: F401 (fixtures)


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
    # the setup lines name the checkpoints from the project root, the same on every machine
    named = ", ".join(f"{f}: models/{f}/model.ckpt" for f in FAMILIES)
    for text in (table, robustness, coherence_md):
        assert f"Checkpoints: {named}." in text
        assert str(trained_root) not in text
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


D, LATENT, STD = 200, 4, 0.1  # the trajectory likelihood's shape and std


def _model(seed=0):
    g = torch.Generator().manual_seed(seed)
    w = torch.randn(D, LATENT, generator=g) * 0.2
    b = torch.randn(D, generator=g) * 0.1
    x = (torch.randn(6, LATENT, generator=g) @ w.T + b) + STD * torch.randn(6, D, generator=g)
    return w, b, x


def _exact(w, b, x, std=STD):
    cov = w @ w.T + std**2 * torch.eye(D)
    return torch.distributions.MultivariateNormal(b, covariance_matrix=cov).log_prob(x)


def _posterior(w, b, x, std=STD):
    precision = torch.eye(LATENT) + w.T @ w / std**2
    cov = torch.linalg.inv(precision)
    mean = (x - b) @ w @ cov.T / std**2
    return mean, torch.log(torch.diagonal(cov)).expand_as(mean), cov


def _path(mu, logvar, w, b):
    return ImportancePath(Gaussian(mu, logvar), lambda z: z @ w.T + b, "traj", LATENT)


def test_matches_the_closed_form_with_a_good_proposal():
    """Tolerance 0.05 nats per sample at K = 2000 (measured error 0.005)."""
    w, b, x = _model()
    mean, logvar, _ = _posterior(w, b, x)
    # the diagonal of the exact posterior: near-exact, small variance
    est = iw_log_likelihood(
        _path(mean, logvar, w, b),
        x,
        Likelihoods(STD),
        k=2000,
        generator=torch.Generator().manual_seed(1),
    )
    torch.testing.assert_close(est, _exact(w, b, x), atol=0.05, rtol=0)


def test_tightens_as_k_grows_with_a_poor_proposal():
    w, b, x = _model(1)
    mean, logvar, _ = _posterior(w, b, x)
    poor = _path(mean + 0.5 * torch.exp(0.5 * logvar), logvar + 1.0, w, b)  # off and too wide
    exact = _exact(w, b, x)
    gaps = []
    for k in (1, 10, 100, 1000, 5000):
        est = iw_log_likelihood(
            poor, x, Likelihoods(STD), k=k, generator=torch.Generator().manual_seed(k)
        )
        gaps.append((exact - est).mean().item())
    # measured: 3.01, -0.05, 0.04, -0.003, 0.0002 nats (seeded); K = 1 is the loose ELBO-like
    # bound, K = 1000 and 5000 are within the stated tolerances of the exact value
    assert gaps[0] > 1.0
    assert abs(gaps[3]) < 0.05
    assert abs(gaps[4]) < 0.02
    assert abs(gaps[4]) < 0.05 * gaps[0]


def test_chunking_does_not_change_the_estimate():
    """Drawn in chunks of 50 or all at once from the same seeded stream: the same samples, so
    the running log-sum-exp must give the same estimate (bounded memory costs nothing). (torch's
    CPU sampler keeps one stream only for draws of a multiple of 16 values; chunks of 7 draw
    other samples and agree within Monte Carlo error.)"""
    w, b, x = _model(2)
    mean, logvar, _ = _posterior(w, b, x)
    path = _path(mean + 0.5 * torch.exp(0.5 * logvar), logvar, w, b)

    def estimate(chunk):
        g = torch.Generator().manual_seed(3)
        return iw_log_likelihood(path, x, Likelihoods(STD), k=300, chunk=chunk, generator=g)

    whole = estimate(300)
    torch.testing.assert_close(estimate(50), whole, atol=1e-4, rtol=0)
    assert (estimate(7) - whole).abs().max() < 0.5


@pytest.mark.parametrize("k", [0, -3, 2.5])
def test_k_below_one_is_refused(k):
    w, b, x = _model()
    mean, logvar, _ = _posterior(w, b, x)
    with pytest.raises(UsageError, match="K must be an integer >= 1"):
        iw_log_likelihood(_path(mean, logvar, w, b), x, Likelihoods(STD), k=k)


def test_single_sample_is_the_elbo_estimate():
    w, b, x = _model(3)
    mean, logvar, _ = _posterior(w, b, x)
    g = torch.Generator().manual_seed(5)
    est = iw_log_likelihood(_path(mean, logvar, w, b), x, Likelihoods(STD), k=1, generator=g)
    assert torch.isfinite(est).all()
    assert math.isfinite(float(est.mean()))


def test_several_likelihoods_in_one_pass_equal_separate_passes():
    """One pass under stds 0.1, 1.0 and 0.3 (shared latent samples and decoder outputs) gives,
    row by row, what a separate pass with the same seed gives."""
    w, b, x = _model(4)
    mean, logvar, _ = _posterior(w, b, x)
    path = _path(mean + 0.3 * torch.exp(0.5 * logvar), logvar + 0.5, w, b)
    stds = (STD, 1.0, 0.3)
    together = iw_log_likelihoods(
        path,
        x,
        [Likelihoods(s) for s in stds],
        k=400,
        chunk=80,
        generator=torch.Generator().manual_seed(7),
    )
    assert together.shape == (3, len(x))
    for row, std in zip(together, stds):
        alone = iw_log_likelihood(
            path, x, Likelihoods(std), k=400, chunk=80, generator=torch.Generator().manual_seed(7)
        )
        torch.testing.assert_close(row, alone, atol=1e-4, rtol=0)
    assert (together[0] - together[1]).abs().min() > 50  # different conventions, not one copied


def test_unit_variance_row_matches_its_closed_form():
    """Scored under std 1 (Table I's main convention), with the std-1 posterior as proposal, the
    estimate is the exact log N(x; b, W W^T + I), while the std-0.1 row of the same pass is a
    different number (its own density)."""
    w, b, x = _model(5)
    mean, logvar, _ = _posterior(w, b, x, std=1.0)
    est = iw_log_likelihoods(
        _path(mean, logvar, w, b),
        x,
        [Likelihoods(1.0), Likelihoods(STD)],
        k=2000,
        generator=torch.Generator().manual_seed(2),
    )
    torch.testing.assert_close(est[0], _exact(w, b, x, std=1.0), atol=0.05, rtol=0)
    assert (est[1] - _exact(w, b, x, std=1.0)).abs().min() > 50


def test_an_empty_list_of_likelihoods_is_refused():
    w, b, x = _model()
    mean, logvar, _ = _posterior(w, b, x)
    with pytest.raises(UsageError, match="no likelihood"):
        iw_log_likelihoods(_path(mean, logvar, w, b), x, [], k=3)
