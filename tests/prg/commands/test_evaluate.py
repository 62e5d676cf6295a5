"""Tests of ``prg.commands.evaluate`` (moved from the suite on: `prg-evaluate`: Table I, coherence
and robustness reports from real (tiny) trained models, written atomically, logged to a real
SQLite MLflow store; bad input gets one line)."""

import pytest

from tests.helpers.evaluate import _cfg

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
