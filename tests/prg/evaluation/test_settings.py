"""`prg-evaluate`: Table I, coherence and robustness reports from real (tiny) trained models,
written atomically, logged to a real SQLite MLflow store; bad input gets one line."""

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
