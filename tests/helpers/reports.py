"""Helpers shared by the tests that were split out of tests/test_reports.py."""

from prg.evaluation.likelihood import PAPER_TABLE1


def _lk(cell, value, sem=0.5, std=None, model="avae_ts"):
    return {
        "model": model,
        "family": "avae_ts",
        "cell": cell,
        "value": value,
        "sem": sem,
        "traj_std": std,
        "paper": PAPER_TABLE1["avae_ts"].get(cell),
    }


def _coh(target, given, kind, exact, folded, model="muse"):
    return {
        "model": model,
        "family": "muse",
        "target": target,
        "given": given,
        "kind": kind,
        "temperature": 0.0 if kind == "mean" else 1.0,
        "coherence": exact,
        "coherence_folded": folded,
        "n": 40,
    }


COHERENCE = [
    _coh("traj", "S", "mean", 0.5124, 0.6876),
    _coh("traj", "S", "sampled", 0.3124, 0.4376),
    _coh("traj", "T,S", "mean", 0.875, 0.9),
    _coh("traj", "T,S", "sampled", 0.8, 0.825),
]


SMOOTHNESS = [
    {
        "model": "muse",
        "family": "muse",
        "target": "traj",
        "given": "S",
        "roughness": 0.4321,
        "reference": 0.2,
        "ratio": 2.1605,
        "n": 40,
    }
]
