"""Tests of ``prg.commands.paper_scale`` (moved from the suite on: ``python -m
prg.commands.paper_scale`` (``make paper``): the whole path on the CPU with a tiny budget — four
concurrent trainings and the classifiers, then the evaluation into its own folder — and its
failures: bad options (one line, exit 2, nothing started) and a training that fails (one line,
exit 1, the other processes stopped))."""

from __future__ import annotations

import pytest

from prg.commands import paper_scale


@pytest.mark.parametrize(
    "args, expected",
    [
        (["--families", "cvae,gan"], "--families 'cvae,gan': unknown 'gan'; choose from cvae"),
        (["--families", "muse,muse"], "a family is named twice"),
        (["--epochs", "0"], "argument --epochs: must be >= 1, got '0'"),
        (["--no-such-option"], "unrecognized arguments: --no-such-option"),
        (["--train-set", "muse:nokey"], "--train-set 'muse:nokey': expected [FAMILY:]KEY=VALUE"),
        (["--train-set", "gan:seed=1"], "unknown family 'gan'"),
        (["--device", "cpu", "--train-set", "trainer.nope=1"], "--train-set (cvae): "),
        (["--device", "cpu", "--eval-set", "likelihood.nope=1"], "--eval-set: "),
    ],
)
def test_bad_options_are_one_line_with_exit_2_before_anything_starts(
    args, expected, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        paper_scale.main(args)
    assert exit_info.value.code == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("prg.commands.paper_scale: error: "), (
        captured.err
    )
    assert expected in lines[0]
    assert captured.out == ""
    assert list(tmp_path.iterdir()) == []  # no folder, no process


def test_cuda_without_a_gpu_is_refused_with_one_line(tmp_path, monkeypatch, capsys):
    import torch

    if torch.cuda.is_available():
        pytest.skip("a GPU is visible")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        paper_scale.main([])  # make paper's default: --device cuda
    assert exit_info.value.code == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert "--device cuda: torch" in line and "sees no GPU" in line and "--device cpu" in line
