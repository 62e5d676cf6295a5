"""The README's Python snippet runs as written: the library path from a command to the robot."""

from __future__ import annotations

import re
import sys

import numpy as np

from tests.conftest import REPO


def readme_snippet() -> str:
    text = (REPO / "README.md").read_text()
    match = re.search(r"<!-- api-snippet -->\n```python\n(.*?)```", text, re.S)
    assert match, "README.md has no api-snippet block"
    return match.group(1)


def test_the_readme_snippet_writes_a_word_and_the_robot_writes_it(
    untrained_muse_checkpoint, tmp_path, monkeypatch
):
    code = readme_snippet()
    assert len(code.strip().splitlines()) == 3  # the README promises three lines
    assert '"models/muse/model.ckpt"' in code
    code = code.replace('"models/muse/model.ckpt"', repr(str(untrained_muse_checkpoint)))
    monkeypatch.chdir(tmp_path)
    torch_state = sys.modules.get("torch")
    if torch_state is not None:
        torch_state.manual_seed(0)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    result, robot = namespace["result"], namespace["robot"]
    assert result.text == "joy" and result.letters.shape == (3, 100, 2)
    assert result.word.dmp.n_basis >= 20 and result.word.duration_s > 0
    assert set(result.timings) == {"perceive", "decode", "compose", "total"}
    # the arm inked the word where the DMP told it to, to within a millimetre on average
    assert robot.text == "joy" and robot.contact.any()
    assert np.isfinite(robot.metrics["tracking_error_mean_mm"])
    assert robot.metrics["tracking_error_mean_mm"] < 1.0
