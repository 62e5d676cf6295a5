"""A written word exported to real machines (prg.export, prg-export): every file is read back
with another reader (gcodeparser, an HPGL parser written here, vpype's SVG reader, mcap-ros2's
reader, numpy) and compared with what the word, its DMP timing and the simulated arm say
independently; the joint-limit check slows a too-fast timing by the smallest factor and refuses
what no slow-down fixes."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from tests.conftest import run_cli
from tests.helpers.export import _timed, parse_gcode, read_mcap, word  # noqa: F401 (fixtures)


def test_prg_export_writes_every_format_and_refuses_bad_input_writing_nothing(word, tmp_path):
    source = word.to_json(tmp_path / "hi.json")
    out = tmp_path / "out"
    common = [f"paths.root_dir={tmp_path}", f"out_dir={out}"]
    done = run_cli("prg-export", f"word={source}", *common)
    assert done.returncode == 0, done.stderr
    names = {p.name for p in out.iterdir()}
    assert names == {"word.gcode", "word.hpgl", "word.svg", "word.mcap", "word.csv", "export.json"}
    meta = json.loads((out / "export.json").read_text())
    assert meta["text"] == "h i" and meta["robot"]["timing"]["slow_down"] == 1.0
    _, seconds = parse_gcode((out / "word.gcode").read_text())
    assert seconds == pytest.approx(_timed(word)[1], rel=1e-3)
    assert len(read_mcap(out / "word.mcap")["/joint_trajectory"].ros_msg.points) == len(
        np.loadtxt(out / "word.csv", delimiter=",", skiprows=1)
    )
    fresh = tmp_path / "fresh"
    missing = run_cli(
        "prg-export", f"word={tmp_path / 'nope.json'}", *common[:1], f"out_dir={fresh}"
    )
    assert missing.returncode == 2
    assert re.fullmatch(
        r"prg-export: error: .*nope\.json: no such word trajectory file\n", missing.stderr
    )
    too_big = run_cli("prg-export", f"word={source}", "scale=30", *common[:1], f"out_dir={fresh}")
    assert too_big.returncode == 2 and too_big.stderr.count("\n") == 1
    assert "does not fit" in too_big.stderr
    assert not fresh.exists()


def test_prg_export_puts_each_word_in_a_new_folder_by_default(word, tmp_path):
    source = word.to_json(tmp_path / "hi.json")
    runs = [
        run_cli("prg-export", f"word={source}", f"paths.root_dir={tmp_path}", "formats=[svg]")
        for _ in range(2)
    ]
    assert all(r.returncode == 0 for r in runs), runs[-1].stderr
    folders = sorted((tmp_path / "outputs/export").iterdir())
    assert len(folders) == 2  # the second run did not overwrite the first
    for folder in folders:
        assert re.fullmatch(r"h_i-\d{8}-\d{6}(-2)?", folder.name), folder.name
        assert {p.name for p in folder.iterdir()} == {"word.svg", "export.json"}
