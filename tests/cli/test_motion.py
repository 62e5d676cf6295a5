"""``motion.csv``, the word's timed pen motion that ``prg-write`` saves, comes from the generation
pipeline (:mod:`prg.pipeline.motion`): writing it loads neither the simulator nor PyBullet, and
:mod:`prg.sim` re-exports the same functions."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from tests.conftest import REPO

# A fresh interpreter saves a word as prg-write does (WriteResult.save, without the recording)
# and prints which simulator modules it loaded on the way.
SAVE_A_WORD = """
import json, sys
import numpy as np
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.dmp import rollout
from prg.pipeline.word import WordTrajectory
from prg.writer import WriteResult

word = WordTrajectory.from_json(sys.argv[1])
body = rollout(word.dmp)
WriteResult(None, GenerateSettings(), "muse", np.zeros((0, 100, 2)), word, body).save(sys.argv[2])
loaded = [m for m in sys.modules if m == "pybullet" or m == "prg.sim" or m.startswith("prg.sim.")]
print(json.dumps(sorted(loaded)))
"""


def test_saving_a_word_writes_motion_csv_without_the_simulator(tmp_path):
    from prg.pipeline.compose import GenerateSettings
    from prg.sim import font_word

    word = font_word("ab it")  # a space (pen up) and delayed strokes (the dot, the bar)
    word.to_json(tmp_path / "word.json")
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-c", SAVE_A_WORD, str(tmp_path / "word.json"), str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    assert json.loads(result.stdout.splitlines()[-1]) == []  # no prg.sim, no pybullet

    motion = np.loadtxt(out / "motion.csv", delimiter=",", skiprows=1)  # t, x, y, pen_down
    from prg.sim import word_samples  # the simulator's name for the same motion

    xy, t, down = word_samples(word, 1.0 / GenerateSettings().samples_per_s)
    np.testing.assert_allclose(motion[:, 0], t, atol=1e-6)
    np.testing.assert_allclose(motion[:, 1:3], xy, atol=1e-6)
    np.testing.assert_array_equal(motion[:, 3].astype(bool), down)
    assert not down.all() and down.any()
