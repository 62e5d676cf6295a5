"""Tests of ``prg.writer`` (moved from the suite on: the README's Python snippet runs as written:
the library path from a command to the robot)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import torch
from mlflow import MlflowClient

from prg.alphabet import char_to_label
from prg.errors import UsageError
from prg.models.muse import MUSE
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.decode import label_inputs
from prg.pipeline.timing import timed_body
from prg.pipeline.word import WordTrajectory
from prg.writer import Perception, Writer
from tests.conftest import stand_in_hands
from tests.helpers.serving import library_rollout, trained  # noqa: F401 (fixtures)


def test_a_writer_takes_arrays_for_every_channel_and_loads_its_model_once(
    untrained_muse_checkpoint, tmp_path
):
    import pytest

    from prg import Writer
    from prg.errors import UsageError

    writer = Writer.from_checkpoint(untrained_muse_checkpoint)
    model = writer.model
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 40)
    strokes = [np.stack([t, np.sin(3 * t + k)], axis=1) for k in range(3)]
    images = [(rng.random((28, 28)) > 0.8) * 255.0 for _ in range(3)]
    given = writer.perceive(images=images, trajectories=strokes, spelling="cat", read=True)
    assert given.text == "cat" and set(given.inputs) == {"image", "traj"}  # no label input
    assert given.read is not None and len(given.read) == 3  # what the model read, reported
    result = writer.generate(given)
    assert result.text == "cat" and writer.model is model
    folder = result.save(tmp_path / "out", record=False)
    assert sorted(p.name for p in folder.iterdir()) == [
        "dmp_rollout.csv",
        "motion.csv",
        "word.json",
        "word.png",
        "word.svg",
    ]
    with pytest.raises(UsageError, match="text and audio both give the S channel"):
        writer.perceive(text="cat", audio=tmp_path / "cat.wav")
    with pytest.raises(UsageError, match="nothing to write"):
        writer.write()
    with pytest.raises(UsageError, match="images= gives 2 letters"):
        writer.write(text="cat", images=images[:2])


def test_saving_a_word_into_a_used_folder_leaves_no_stale_recording(
    untrained_muse_checkpoint, tmp_path
):
    from prg import Writer

    writer = Writer.from_checkpoint(untrained_muse_checkpoint)
    folder = tmp_path / "out"
    writer.write(text="ab").save(folder, record=True)
    assert (folder / "word.rrd").is_file()
    (folder / "notes.txt").write_text("the user's own file\n")
    writer.write(text="cd").save(folder, record=False)
    assert not (folder / "word.rrd").exists()  # the recording of "ab" would sit beside "cd"
    assert (folder / "notes.txt").read_text() == "the user's own file\n"
    assert WordTrajectory.from_json(folder / "word.json").text == "cd"


def test_a_warm_writer_decodes_each_label_once_and_gives_the_same_letters(
    untrained_muse_checkpoint,
):
    """Letters from labels alone at temperature 0 are decoded once per writer and reused; they
    match a fresh writer's to float32 rounding, and sampling (temperature > 0) is not reused."""
    from dataclasses import replace

    from prg import Writer
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.decode import decode_letters, label_inputs

    posterior = GenerateSettings(mode="posterior")
    writer = Writer.from_checkpoint(untrained_muse_checkpoint, settings=posterior)
    cat = writer.write(text="cat").letters
    act = writer.write(text="act").letters
    np.testing.assert_array_equal(act, cat[[1, 0, 2]])  # the same arrays, reused
    fresh = Writer.from_checkpoint(untrained_muse_checkpoint, settings=posterior)
    fresh = fresh.write(text="act").letters
    np.testing.assert_allclose(act, fresh, atol=1e-5)
    s = writer.settings
    alone = decode_letters(writer.model, label_inputs("act"), 0.0, s.seed, s.impute_steps)
    np.testing.assert_allclose(act, alone, atol=1e-5)
    writer.settings = replace(s, temperature=1.0, seed=1)
    sampled = writer.write(text="cat").letters
    writer.settings = replace(s, temperature=1.0, seed=2)
    assert np.abs(writer.write(text="cat").letters - sampled).max() > 1e-3


def test_a_seed_is_one_hand_another_seed_another(untrained_muse_checkpoint):
    """The default hand mode: one seed writes the same word twice; another seed writes it in
    another writer's hand; the letters of a word come from one writer's letters."""
    from prg import Writer
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.hands import components, random_hand

    def letters(seed, text="abcab"):
        settings = GenerateSettings(seed=seed)
        return Writer.from_checkpoint(untrained_muse_checkpoint, settings=settings).write(text=text)

    first = letters(3)
    np.testing.assert_array_equal(first.letters, letters(3).letters)
    # an untrained decoder moves little with its input: any difference is another hand
    assert np.abs(first.letters - letters(4).letters).mean() > 1e-5
    bank = Writer.from_checkpoint(untrained_muse_checkpoint).hands
    labels = np.array([char_to_label(c) for c in "abcab"])
    chosen = components(bank, random_hand(bank, 3), labels, 3)
    writer = random_hand(bank, 3).writer
    mine = bank.traj[bank.writer == writer]
    assert all(any(np.array_equal(row, m) for m in mine) for row in chosen)


def test_a_style_writes_the_persons_own_letters_for_the_classes_they_gave(
    untrained_muse_checkpoint,
):
    from prg import Writer
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.hands import decode_in_hand, decoder_bias

    writer = Writer.from_checkpoint(untrained_muse_checkpoint)
    own = writer.hands.traj[:2] * 0.5  # a person's "a" and "b", unlike any bank letter
    settings = GenerateSettings(hand_temperature=0.0)
    styled = Writer.from_checkpoint(
        untrained_muse_checkpoint, settings=settings, style=(own, "ab")
    ).write(text="ba")
    labels = np.array([char_to_label("b"), char_to_label("a")])
    bias = decoder_bias(writer.model, writer.hands)
    expected = decode_in_hand(writer.model, own[[1, 0]], labels, 0.0, settings.seed, bias)
    np.testing.assert_allclose(styled.letters, expected, atol=1e-6)


def test_a_model_without_hands_says_how_to_write_without_them():
    from prg import Writer
    from prg.errors import UsageError
    from prg.models.muse import MUSE
    from prg.pipeline.compose import GenerateSettings

    with pytest.raises(UsageError, match=r"generate\.mode=posterior"):
        Writer(MUSE()).write(text="ab")
    assert Writer(MUSE(), GenerateSettings(mode="posterior")).write(text="ab").text == "ab"


def test_a_word_is_laid_out_connected_and_reproduced_by_one_dmp():
    torch.manual_seed(0)
    writer = Writer(MUSE(), GenerateSettings(samples_per_s=150), hands=stand_in_hands())
    result = writer.generate(Perception("ab cd", label_inputs("ab cd")))
    word, path = result.word, result.rollout
    assert [c for c, _ in word.letters] == list("abcd")
    # three joins: the space between the words, and within them a connection each, or a pen-up
    # travel where the writer lifts (prg.pipeline.joins.lifts_pen: untrained letters)
    kinds = word.segment_kinds
    assert kinds.count("connection") + kinds.count("space") == 3 and kinds.count("space") >= 1
    assert word.dmp.n_basis >= 20 and word.duration_s > 0
    demo, _ = timed_body(word.body, result.settings)
    assert path.shape == demo.shape
    rmse = np.sqrt(((path - demo) ** 2).sum(1).mean())
    # cm: untrained decoders give jittery letters (measured 0.07); a quick AVAE(T,S) "hello
    # world" reproduces to 0.015 cm
    assert rmse < 0.1


def test_inputs_must_match_the_letters():
    with pytest.raises(UsageError, match=r"images= gives 2 letters but the text .* has 3 letters"):
        Writer(MUSE()).generate(Perception("abc", {"image": torch.rand(2, 1, 28, 28)}))


def test_every_training_run_logs_a_servable_model(trained):
    import mlflow

    run = MlflowClient(trained["uri"]).get_run(trained["run_id"])
    model_uri = run.data.tags["prg.model_uri"]
    mlflow.set_tracking_uri(trained["uri"])
    model = mlflow.pyfunc.load_model(model_uri)
    inputs = [c.name for c in model.metadata.signature.inputs.inputs]
    assert inputs == ["text", "trajectories"]
    out = model.predict(pd.DataFrame({"text": ["cat", "ox"]}))
    assert list(out["text"]) == ["cat", "ox"]
    for text, rollout in zip(out["text"], out["rollout"]):
        expected = library_rollout(trained["ckpt"], text=text)
        assert np.allclose(np.array(json.loads(rollout)), expected, atol=1e-5)
    word = json.loads(out["word"][0])
    assert word["schema"] == "prg.word_trajectory" and word["dmp"]["n_basis"] > 0
    assert out["duration_s"][0] == pytest.approx(word["duration_s"])


def test_a_row_of_letter_trajectories_alone_is_read_and_written(trained):
    import mlflow

    mlflow.set_tracking_uri(trained["uri"])
    tags = MlflowClient(trained["uri"]).get_run(trained["run_id"]).data.tags
    model = mlflow.pyfunc.load_model(tags["prg.model_uri"])
    t = np.linspace(0, 2 * np.pi, 60)
    strokes = [np.column_stack([np.cos(t), np.sin(t)]).tolist(), [[0, 0], [0, 1], [0, 2]]]
    out = model.predict(pd.DataFrame({"trajectories": [json.dumps(strokes)]}))
    expected = library_rollout(trained["ckpt"], trajectories=[np.array(s) for s in strokes])
    assert len(out["text"][0]) == 2
    assert np.allclose(np.array(json.loads(out["rollout"][0])), expected, atol=1e-5)
    with pytest.raises(Exception, match="give a text, trajectories or both"):
        model.predict(pd.DataFrame({"text": [None], "trajectories": [None]}))
