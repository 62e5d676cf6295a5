"""Tests of ``prg.evaluation.run`` (moved from the suite on: report text of `prg-evaluate` from
hand-made result rows: Table I's two trajectory conventions, exact and folded coherence, the
smoothness section, the metric keys)."""

import math

import pytest

from prg.evaluation.run import Evaluation, metrics_of
from tests.helpers.reports import COHERENCE, SMOOTHNESS, _lk


def test_metric_keys():
    smoothness = [*SMOOTHNESS, {**SMOOTHNESS[0], "given": "I", "ratio": math.nan}]
    result = Evaluation(
        table1=[_lk("logp_T", -196.0, std=1.0), _lk("logp_T_model_std", 206.0, std=0.1)],
        coherence=COHERENCE,
        smoothness=smoothness,
    )
    metrics = metrics_of(result)
    assert metrics["avae_ts/logp_T"] == -196.0
    assert metrics["avae_ts/logp_T_model_std"] == 206.0
    assert metrics["muse/coherence_T_given_S"] == pytest.approx(0.5124)
    assert metrics["muse/coherence_folded_T_given_S"] == pytest.approx(0.6876)
    assert metrics["muse/coherence_sampled_T_given_TS"] == pytest.approx(0.8)
    assert metrics["muse/coherence_folded_sampled_T_given_TS"] == pytest.approx(0.825)
    assert metrics["muse/roughness_ratio_T_given_S"] == pytest.approx(2.1605)
    assert metrics["test_split/roughness"] == pytest.approx(0.2)
    assert "muse/roughness_ratio_T_given_I" not in metrics  # NaN is left out of the JSON
    assert all(math.isfinite(v) for v in metrics.values())


def test_metric_keys_of_the_second_classifier_and_agreement():
    second = {
        "coherence_second": 0.25,
        "coherence_folded_second": 0.375,
        "agreement": 0.4,
        "agreement_folded": 0.5,
        "difference": 0.2624,
        "difference_folded": 0.3126,
        "coherence_folded_both": 0.3,
    }
    label_row = {**COHERENCE[0], "target": "label", **dict.fromkeys(second)}  # no 2nd reading
    rows = [{**COHERENCE[0], **second}, {**COHERENCE[1], **second}, label_row]
    classifiers = {"traj": {"test_accuracy": 0.9}, "traj_rendered": {"test_accuracy": 0.8}}
    metrics = metrics_of(Evaluation(coherence=rows, classifiers=classifiers))
    assert metrics["muse/coherence_T_given_S"] == pytest.approx(0.5124)  # the main keys stay
    assert metrics["muse/coherence_second_T_given_S"] == pytest.approx(0.25)
    assert metrics["muse/coherence_folded_second_T_given_S"] == pytest.approx(0.375)
    assert metrics["muse/agreement_T_given_S"] == pytest.approx(0.4)
    assert metrics["muse/agreement_folded_sampled_T_given_S"] == pytest.approx(0.5)
    assert metrics["classifier/traj_rendered/test_accuracy"] == pytest.approx(0.8)
    assert not any(k.startswith("muse/agreement_S_") for k in metrics)  # labels: none
