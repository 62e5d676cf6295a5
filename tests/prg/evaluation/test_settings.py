"""Tests of ``prg.evaluation.settings`` (moved from the suite on: `prg-evaluate`: Table I,
coherence and robustness reports from real (tiny) trained models, written atomically, logged to
a real SQLite MLflow store; bad input gets one line)."""

import pytest

from prg.commands.cli import compose_config
from prg.evaluation.likelihood import TABLE1_CELLS


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


def test_the_module_imports_no_numpy_or_torch():
    # prg-evaluate checks its config against the ranges declared here before loading either
    import subprocess
    import sys

    code = (
        "import sys, prg.evaluation.settings as s; s.EvaluationSettings(); "
        "print('numpy' in sys.modules, 'torch' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False False"


def test_the_modules_that_use_the_defaults_export_the_same_values():
    from prg.evaluation import classifiers, likelihood, settings

    assert likelihood.PAPER_TRAJ_STD == settings.PAPER_TRAJ_STD == 1.0
    assert classifiers.DEFAULT_CFG is settings.DEFAULT_CFG
    assert settings.LikelihoodSettings().traj_std == settings.PAPER_TRAJ_STD


def test_unknown_cells_are_named_with_the_table_i_cells():
    from prg.errors import SettingsError
    from prg.evaluation.settings import LikelihoodSettings

    with pytest.raises(SettingsError, match=r"^cells \['logp_X'\]: use 'all' or a list of"):
        LikelihoodSettings(cells=["logp_X"])
    assert LikelihoodSettings(cells="logp_S").cells == ("logp_S",)
