"""`prg-evaluate`: Table I, coherence and robustness reports from real (tiny) trained models,
written atomically, logged to a real SQLite MLflow store; bad input gets one line."""

import pytest

from tests.conftest import run_cli
from tests.helpers.evaluate import TINY, trained_root  # noqa: F401 (fixtures)


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
    assert {"traj.pt", "image.pt", "image_knn.npz", "metrics.json"} <= {
        p.name for p in folder.iterdir()
    }
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
