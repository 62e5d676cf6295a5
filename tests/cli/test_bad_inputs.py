"""Bad input to every command: one line naming the problem, exit code 2 (usage) or 1 (run
time), no traceback, and nothing written.

One table, ``CASES``, covers the eight commands. ``{name}`` placeholders in a case's arguments
are files made once by :func:`bad_files` (a corrupt WAV, a text file named ``.ckpt``, a
truncated checkpoint ...); ``{tmp}`` is the test's own folder, which is also the working
directory and ``paths.root_dir``, so even a default output path lands where the before/after
snapshot of both folders looks. No file may appear, change or vanish there, except in Hydra's
own log folder (``paths.log_dir``). Each case runs the command's console-script ``main`` in this
process (the function the installed script calls; a subprocess spends seconds importing torch);
``test_console_scripts_behave_the_same`` runs one case of each kind of entry point (Hydra,
argparse) through the installed scripts.

"Unwritable" output: the tests run as root, whom file modes do not stop, so the output paths
are ones no user can create: below a regular file, and below ``/sys`` (sysfs refuses new
folders, root included).
"""

from __future__ import annotations

import importlib.metadata
import json
import logging
import os
import struct
import sys
import wave
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import REPO, run_cli

HYDRA_COMMANDS = (
    "prg-prepare",
    "prg-train",
    "prg-evaluate",
    "prg-write",
    "prg-dictaphone",
    "prg-simulate",
    "prg-export",
)


@dataclass(frozen=True)
class Case:
    id: str
    command: str
    args: tuple[str, ...]
    code: int  # 2: usage error, 1: run-time failure
    expected: str  # the one line must contain this


def case(id: str, command: str, args: str | list[str], code: int, expected: str) -> Case:
    return Case(id, command, tuple(args.split() if isinstance(args, str) else args), code, expected)


CASES = [
    # ---- prg-prepare
    case("prepare-negative-count", "prg-prepare", "data.augment.per_class=-5", 2, "per_class"),
    case("prepare-non-numeric", "prg-prepare", "data.synthetic.n_writers=many", 2, "n_writers"),
    case(
        "prepare-uji-garbage", "prg-prepare", "data=uji data.uji_path={garbage}", 2, "garbage.txt"
    ),
    case("prepare-uji-folder", "prg-prepare", "data=uji data.uji_path={folder}", 2, "a-folder"),
    case(
        "prepare-out-below-file",
        "prg-prepare",
        "data.synthetic.n_writers=5 paths.data_dir={file}/data",
        2,
        "a-file.txt",
    ),
    case(
        "prepare-metrics-in-sys",
        "prg-prepare",
        "data.synthetic.n_writers=5 metrics_path=/sys/prg/m.json",
        2,
        "/sys/prg",
    ),
    case(
        "prepare-download-bad-archive",
        "prg-prepare",
        "data=uji data.download=true data.uji_url=file://{garbage}",
        1,
        "checksum",
    ),
    case(
        "prepare-download-refused",
        "prg-prepare",
        "data=uji data.download=true data.uji_url=http://127.0.0.1:9/uji.zip",
        1,
        "127.0.0.1:9",
    ),
    case("prepare-log-dir-below-file", "prg-prepare", "paths.log_dir={file}/logs", 2, "a-file.txt"),
    # numbers out of range (prg.checks.RANGES), unresolvable interpolations, broken source files
    case("prepare-zero-val-split", "prg-prepare", "data.splits.val=0", 2, "data.splits.val"),
    case("prepare-nan-split", "prg-prepare", "data.splits.test=nan", 2, "data.splits.test"),
    case("prepare-inf-sigma", "prg-prepare", "data.preprocess.smooth_sigma=inf", 2, "smooth_sigma"),
    case("prepare-zero-image-size", "prg-prepare", "data.image.size=0", 2, "data.image.size"),
    case("prepare-huge-seed", "prg-prepare", "data.seed=99999999999999999999", 2, "data.seed"),
    case(
        "prepare-huge-per-class", "prg-prepare", "data.augment.per_class=1000000000", 2, "per_class"
    ),
    case(
        "prepare-uji-coordinate-beyond-int64",
        "prg-prepare",
        "data=uji data.uji_path={uji_overflow}",
        2,
        "overflow.txt, line 3: coordinate 99999999999999999999 is out of range",
    ),
    case(
        "prepare-unresolvable-env",
        "prg-prepare",
        "metrics_path=${{oc.env:PRG_NO_SUCH_VAR}}/m.json",
        2,
        "metrics_path=${oc.env:PRG_NO_SUCH_VAR}/m.json cannot be resolved",
    ),
    # ---- prg-train
    case("train-non-numeric", "prg-train", "trainer.max_epochs=banana", 2, "max_epochs"),
    case("train-negative-seed", "prg-train", "seed=-1", 2, "seed"),
    case("train-no-dataset", "prg-train", "paths.data_dir={tmp}/nodata", 2, "prg-prepare"),
    case("train-text-ckpt", "prg-train", "ckpt_path={text_ckpt}", 2, "notes.ckpt"),
    case("train-truncated-ckpt", "prg-train", "ckpt_path={truncated_ckpt}", 2, "truncated.ckpt"),
    case("train-ckpt-is-a-folder", "prg-train", "ckpt_path={folder}", 2, "is a folder"),
    case("train-export-below-file", "prg-train", "export_dir={file}/m", 2, "export_dir"),
    case("train-ckpt-dir-in-sys", "prg-train", "checkpoint_dir=/sys/prg/ckpt", 2, "/sys/prg"),
    case("train-huge-seed", "prg-train", "seed=99999999999999999999", 2, "seed must be"),
    case("train-seed-2-64", "prg-train", "seed=18446744073709551616", 2, "4,294,967,295"),
    case("train-negative-lr", "prg-train", "model.module.optimizer.lr=-1", 2, "optimizer.lr"),
    case("train-nan-lr", "prg-train", "model.module.optimizer.lr=nan", 2, "optimizer.lr"),
    case("train-zero-batch", "prg-train", "model.batch_size=0", 2, "model.batch_size"),
    case("train-inf-limit", "prg-train", "trainer.limit_train_batches=inf", 2, "limit_train"),
    case(
        "train-nan-kl-weight", "prg-train", "model=cvae model.module.model.kl_weight=nan", 2, "kl"
    ),
    case(
        "train-truncated-manifest",
        "prg-train",
        "paths.data_dir={cut_manifest}",
        2,
        "not readable JSON",
    ),
    case(
        "train-manifest-a-list", "prg-train", "paths.data_dir={list_manifest}", 2, "manifest.json"
    ),
    case(
        "train-n-points-mismatch",
        "prg-train",
        "paths.data_dir={points50}",
        2,
        "data.preprocess.n_points=50, but the models take data.preprocess.n_points=100",
    ),
    case(
        "train-image-size-mismatch",
        "prg-train",
        "paths.data_dir={size20}",
        2,
        "data.image.size=20, but the models take data.image.size=28",
    ),
    case("train-empty-val-split", "prg-train", "paths.data_dir={no_val}", 2, "val.npz is empty"),
    case(
        "train-unresolvable-key",
        "prg-train",
        "model.module.optimizer.lr=${{no.such.key}}",
        2,
        "model.module.optimizer.lr=${no.such.key} cannot be resolved",
    ),
    # ---- prg-evaluate
    case("evaluate-missing-models", "prg-evaluate", "families=[muse]", 2, "does not exist"),
    case(
        "evaluate-truncated-ckpt", "prg-evaluate", "+checkpoints.m={truncated_ckpt}", 2, "truncated"
    ),
    case("evaluate-zero-k", "prg-evaluate", "likelihood.k_marginal=0", 2, "k_marginal"),
    case(
        "evaluate-non-numeric-temperature",
        "prg-evaluate",
        "coherence.temperatures.mean=hot",
        2,
        "temperatures.mean",
    ),
    case("evaluate-no-test-split", "prg-evaluate", "+checkpoints.m={ckpt}", 2, "test.npz"),
    case(
        "evaluate-report-below-file",
        "prg-evaluate",
        "+checkpoints.m={ckpt} report_dir={file}/reports",
        2,
        "a-file.txt",
    ),
    case(
        "evaluate-nan-temperature",
        "prg-evaluate",
        "coherence.temperatures.sampled=nan",
        2,
        "sampled",
    ),
    case("evaluate-inf-k", "prg-evaluate", "likelihood.k_conditional=inf", 2, "k_conditional"),
    case("evaluate-huge-seed", "prg-evaluate", "seed=18446744073709551616", 2, "seed must be"),
    case("evaluate-zero-classifier-lr", "prg-evaluate", "classifier.lr=0", 2, "classifier.lr"),
    case("evaluate-zero-n-test", "prg-evaluate", "n_test=0", 2, "n_test"),
    case(
        "evaluate-n-points-mismatch",
        "prg-evaluate",
        "+checkpoints.m={ckpt} paths.data_dir={points50}",
        2,
        "data.preprocess.n_points=50",
    ),
    # ---- prg-write
    case("write-unknown-characters", "prg-write", "text=h@llo", 2, "'@'"),
    case("write-empty-text", "prg-write", "text=", 2, "text is empty"),
    case("write-corrupt-audio", "prg-write", "audio={corrupt_wav}", 2, "corrupt.wav"),
    case("write-silent-audio", "prg-write", "audio={silent_wav}", 2, "silent"),
    case("write-empty-audio", "prg-write", "audio={empty_wav}", 2, "empty"),
    case("write-audio-is-a-folder", "prg-write", "audio={folder}", 2, "a-folder"),
    case("write-text-as-image", "prg-write", "images={text_png}", 2, "letters.png"),
    case("write-blank-image", "prg-write", "images={blank_png}", 2, "blank"),
    case("write-huge-image", "prg-write", "images={huge_png}", 2, "huge.png"),
    case("write-noise-photo", "prg-write", "text=cat images={noise_jpg}", 2, "3 letters"),
    case("write-truncated-ckpt", "prg-write", "text=hi ckpt={truncated_ckpt}", 2, "truncated"),
    case("write-zero-speed", "prg-write", "text=hi generate.speed_cm_s=0", 2, "speed"),
    case("write-zero-threads", "prg-write", "text=hi threads=0", 2, "threads must be"),
    case("write-unknown-flag", "prg-write", "text=hi --frobnicate", 2, "unknown option --frob"),
    case("train-bad-flag-value", "prg-train", "--cfg everything", 2, "invalid choice"),
    case("simulate-flag-missing-value", "prg-simulate", "--config-name", 2, "--config-name"),
    case("write-out-below-file", "prg-write", "text=hi out_dir={file}/out", 2, "a-file.txt"),
    case("write-out-in-sys", "prg-write", "text=hi out_dir=/sys/prg-out", 2, "/sys/prg-out"),
    case("write-out-is-a-file", "prg-write", "text=hi out_dir={file}", 2, "a-file.txt"),
    case(
        "write-nan-temperature", "prg-write", "text=hi generate.temperature=nan", 2, "temperature"
    ),
    case("write-inf-speed", "prg-write", "text=hi generate.speed_cm_s=inf", 2, "speed_cm_s"),
    case(
        "write-huge-temperature", "prg-write", "text=hi generate.temperature=1e300", 2, "in [0, 10]"
    ),
    case(
        "write-huge-letters", "prg-write", "text=hi layout.letter_height=1e300", 2, "letter_height"
    ),
    case(
        "write-zero-letter-height",
        "prg-write",
        "text=hi layout.letter_height=0",
        2,
        "letter_height",
    ),
    case("write-negative-ramp", "prg-write", "text=hi generate.ramp_s=-1", 2, "generate.ramp_s"),
    case("write-huge-seed", "prg-write", "text=hi generate.seed=2e30", 2, "generate.seed"),
    case(
        "write-long-word",
        "prg-write",
        "text=" + "a" * 1000,
        2,
        "1000 letters: accepted are at most",
    ),
    case(
        "write-slow-pen-huge-dmp",
        "prg-write",
        "text=hi generate.speed_cm_s=0.001",
        2,
        "at most 20,000",
    ),
    case("write-long-audio", "prg-write", "audio={long_wav}", 2, "speech.max_seconds=30"),
    case(
        "write-inf-max-seconds",
        "prg-write",
        "audio={silent_wav} speech.max_seconds=inf",
        2,
        "max_seconds",
    ),
    case(
        "write-binary-lexicon",
        "prg-write",
        "audio={silent_wav} speech.lexicon={garbage}",
        2,
        "lexicon",
    ),
    case(
        "write-number-in-lexicon",
        "prg-write",
        "audio={silent_wav} speech.lexicon=[cat,7]",
        2,
        "[1]=7",
    ),
    case(
        "write-unresolvable-env",
        "prg-write",
        "text=hi out_dir=${{oc.env:PRG_NO_SUCH_VAR}}",
        2,
        "PRG_NO_SUCH_VAR",
    ),
    # ---- prg-dictaphone
    case("dictaphone-unknown-characters", "prg-dictaphone", "words=[b@ll]", 2, "'@'"),
    case("dictaphone-no-words", "prg-dictaphone", "words=[]", 2, "words"),
    case("dictaphone-unknown-channel", "prg-dictaphone", "channels=[smell]", 2, "smell"),
    case("dictaphone-negative-speed", "prg-dictaphone", "speed=-5", 2, "speed"),
    case("dictaphone-text-ckpt", "prg-dictaphone", "ckpt={text_ckpt}", 2, "notes.ckpt"),
    case("dictaphone-no-test-split", "prg-dictaphone", "channels=[image]", 2, "test.npz"),
    case("dictaphone-out-below-file", "prg-dictaphone", "out_dir={file}/dict", 2, "a-file.txt"),
    case("dictaphone-word-read-as-bool", "prg-dictaphone", "words=[true]", 2, "words[0]=True"),
    case(
        "dictaphone-word-read-as-number", "prg-dictaphone", "words=[cat,1e3]", 2, "words[1]=1000.0"
    ),
    case("dictaphone-inf-speed", "prg-dictaphone", "speed=inf", 2, "speed must be"),
    case(
        "dictaphone-nan-temperature", "prg-dictaphone", "generate.temperature=nan", 2, "temperature"
    ),
    case(
        "dictaphone-long-word",
        "prg-dictaphone",
        "words=[" + "b" * 70 + "]",
        2,
        "words has 70 letters",
    ),
    case("dictaphone-binary-lexicon", "prg-dictaphone", "speech.lexicon={garbage}", 2, "lexicon"),
    case(
        "dictaphone-n-points-mismatch",
        "prg-dictaphone",
        "channels=[image] paths.data_dir={points50}",
        2,
        "data.preprocess.n_points=50",
    ),
    # ---- prg-simulate
    case("simulate-unknown-robot", "prg-simulate", "word={word} robot=kuka", 2, "kuka"),
    case(
        "simulate-word-too-large",
        "prg-simulate",
        "word={word} scale=40 workspace_step_cm=4",
        2,
        "cm wide",
    ),
    case(
        "simulate-text-too-long",
        "prg-simulate",
        [
            "text='the quick brown fox jumps over the lazy dog'",
            "layout.letter_height=3",
            "workspace_step_cm=4",
            "generate.method=straight",
            "generate.speed_cm_s=100",
        ],
        2,
        "cm wide",
    ),
    case("simulate-corrupt-word", "prg-simulate", "word={bad_json}", 2, "not valid JSON"),
    case("simulate-word-is-a-folder", "prg-simulate", "word={folder}", 2, "a-folder"),
    case("simulate-zero-tempo", "prg-simulate", "word={word} tempo=0", 2, "tempo"),
    case("simulate-non-numeric-scale", "prg-simulate", "word={word} scale=big", 2, "scale"),
    case("simulate-out-below-file", "prg-simulate", "word={word} out_dir={file}/sim", 2, "a-file"),
    case("simulate-text-as-urdf", "prg-simulate", "word={word} robot.urdf={file}", 2, "not a URDF"),
    case(
        "simulate-binary-urdf", "prg-simulate", "word={word} robot.urdf={garbage}", 2, "not a URDF"
    ),
    case(
        "simulate-zero-page-width",
        "prg-simulate",
        "word={word} paper.size_cm=[0,29.7]",
        2,
        "size_cm[0]",
    ),
    case(
        "simulate-zero-camera-width",
        "prg-simulate",
        "word={word} camera.width=0",
        2,
        "camera.width",
    ),
    case("simulate-nan-scale", "prg-simulate", "word={word} scale=nan", 2, "scale must be"),
    case("simulate-huge-scale", "prg-simulate", "word={word} scale=1e300", 2, "scale must be"),
    case("simulate-slow-word", "prg-simulate", "word={slow_word}", 2, "at most 600 s of writing"),
    case("simulate-inf-tempo", "prg-simulate", "word={word} tempo=inf", 2, "tempo must be"),
    case(
        "simulate-negative-time-step",
        "prg-simulate",
        "word={word} control.time_step=-0.01",
        2,
        "time_step",
    ),
    case(
        "simulate-nan-pen-offset",
        "prg-simulate",
        "word={word} robot.pen_offset=[0,0,nan]",
        2,
        "pen_offset[2]",
    ),
    case(
        "simulate-unresolvable-env",
        "prg-simulate",
        "word={word} robot.urdf=${{oc.env:PRG_NO_SUCH_VAR}}",
        2,
        "robot.urdf=${oc.env:PRG_NO_SUCH_VAR} cannot be resolved",
    ),
    case(
        "write-delayed-strokes-not-bool",
        "prg-write",
        "text=hi delayed_strokes=maybe",
        2,
        "delayed_strokes must be true or false",
    ),
    case("write-mark-twice", "prg-write", "text=hi marks.dotted=it", 2, "'t' is also dotted"),
    case("write-zero-dot", "prg-write", "text=hi marks.dot_radius=0", 2, "marks.dot_radius"),
    # unknown keys and choices, answered from the composed command line (prg.commands.cli)
    case(
        "write-unknown-key",
        "prg-write",
        "txt=hello",
        2,
        "unknown key txt (closest: text); accepted top-level keys: text, ",
    ),
    case(
        "write-two-unknown-keys",
        "prg-write",
        "word=hello PRG_ROOT=/elsewhere",
        2,
        "(also unknown: PRG_ROOT); PRG_ROOT looks like an environment variable: put it before",
    ),
    case(
        "write-environment-variable-as-key",
        "prg-write",
        "text=hi PRG_ROOT=/elsewhere",
        2,
        "unknown key PRG_ROOT; accepted top-level keys: text, ",
    ),
    case(
        "write-unreadable-override-among-others",
        "prg-write",
        "text=hi generate.seed=[1 generate.mode=hand",
        2,
        "cannot read generate.seed=[1: no viable alternative at input '[1'; a value with spaces",
    ),
    case(
        "write-group-of-another-command",
        "prg-write",
        "text=hi model=muse",
        2,
        "unknown key model (closest: speech.model, generate.mode); accepted top-level keys: text,",
    ),
    case(
        "write-unknown-family",
        "prg-write",
        "text=hi family=musee",
        2,
        "unknown family musee; accepted: cvae, avae_ts, avae_ti, muse",
    ),
    case(
        "write-top-level-temperature",
        "prg-write",
        "text=hi temperature=-1",
        2,
        "unknown key temperature (closest: generate.temperature",
    ),
    case(
        "write-misspelt-nested-key",
        "prg-write",
        "text=hi generate.temprature=0.5",
        2,
        "(closest: generate.temperature, generate.hand_temperature); accepted under generate: "
        "mode, hand_temperature, temperature, seed",
    ),
    case(
        "write-key-below-a-value",
        "prg-write",
        "text=hi speech.lexicon.cat=1",
        2,
        "unknown key speech.lexicon.cat",
    ),
    case(
        "write-no-model",
        "prg-write",
        "text=hi ckpt=null models_dir={tmp}/nomodels",
        2,
        "nomodels/muse/model.ckpt does not exist: no muse model under models_dir (project root",
    ),
    case(
        "write-no-ckpt-file", "prg-write", "text=hi ckpt=none.ckpt", 2, "/none.ckpt does not exist"
    ),
    case("train-unknown-model", "prg-train", "model=musee", 2, "unknown model musee; accepted:"),
    case("train-unknown-key", "prg-train", "seeed=3", 2, "unknown key seeed (closest: seed"),
    case(
        "evaluate-unknown-family",
        "prg-evaluate",
        "families=[muse,avae]",
        2,
        "unknown family avae in families=['muse', 'avae']; accepted: cvae, avae_ts",
    ),
    case("dictaphone-unknown-family", "prg-dictaphone", "family=vae", 2, "unknown family vae"),
    case("simulate-unknown-key", "prg-simulate", "word={word} robt=iiwa", 2, "closest: robot"),
    case(
        "prepare-unknown-key", "prg-prepare", "worker=3", 2, "unknown key worker (closest: workers"
    ),
    case("export-unknown-key", "prg-export", "word={word} format=[svg]", 2, "closest: formats"),
    # ---- prg-export
    case("export-no-word", "prg-export", [], 2, "give word=WORD.json"),
    case("export-unknown-format", "prg-export", "word={word} formats=[dxf]", 2, "dxf"),
    case("export-word-without-dmp", "prg-export", "word={no_dmp_word}", 2, "DMP"),
    case("export-page-too-small", "prg-export", "word={word} plotter.paper_mm=[20,10]", 2, "mm"),
    case(
        "export-unreachable",
        "prg-export",
        "word={word} formats=[mcap] scale=40 workspace_step_cm=4",
        2,
        "cm wide",
    ),
    case("export-servo-garbage", "prg-export", "word={word} gcode.pen=laser", 2, "gcode.pen"),
    case(
        "export-zero-slow-down", "prg-export", "word={word} limits.max_slow_down=0", 2, "max_slow"
    ),
    # ---- prg-study
    case("study-no-command", "prg-study", [], 2, "choose a command"),
    case("study-missing-file", "prg-study", "build {tmp}/nope.yaml", 2, "no such study file"),
    case("study-bad-yaml", "prg-study", "build {bad_yaml}", 2, "not valid YAML"),
    case("study-bad-value", "prg-study", "build {turing} --set participants=-3", 2, "participants"),
    case(
        "study-build-out-below-file", "prg-study", "build {turing} --out {file}/b", 2, "a-file.txt"
    ),
    case("study-responses-missing", "prg-study", "analyze {tmp}/none.csv", 2, "none.csv"),
    case("study-responses-corrupt", "prg-study", "analyze {bad_csv}", 2, "responses.csv"),
    case("study-alpha-out-of-range", "prg-study", "analyze {bad_csv} --alpha 7", 2, "alpha"),
    case("study-power-out-below-file", "prg-study", "power turing --out {file}/p.csv", 2, "a-file"),
    case("study-power-out-device", "prg-study", "power turing --out /dev/full", 2, "/dev/full"),
    case(
        "study-simulate-zero-participants",
        "prg-study",
        "simulate turing --participants 0 --true-rate 0.2 --out {tmp}/s.csv",
        2,
        "participants",
    ),
    case(
        "study-simulate-out-in-sys",
        "prg-study",
        "simulate turing --participants 3 --true-rate 0.2 --out /sys/prg/s.csv",
        2,
        "/sys/prg",
    ),
    # study settings (a study file's keys or --set), checked in studies.design.study_from_dict
    case(
        "study-negative-alpha", "prg-study", "build {turing} --set alpha=-0.1", 2, "alpha must be"
    ),
    case(
        "study-negative-redirect-delay",
        "prg-study",
        "build {turing} --set completion.redirect_delay_ms=-500",
        2,
        "completion.redirect_delay_ms must be an integer from 0 to",
    ),
    case(
        "study-zero-margin", "prg-study", "build {turing} --set equivalence_margin=0", 2, "margin"
    ),
    case(
        "study-negative-stroke",
        "prg-study",
        "build {turing} --set render.stroke_px=-1",
        2,
        "render.stroke_px must be a positive",
    ),
    case(
        "study-url-without-code",
        "prg-study",
        "build {turing} --set completion.url=https://example.org/done",
        2,
        "has no {code} placeholder",
    ),
    case(
        "study-url-javascript",
        "prg-study",
        "build {turing} --set completion.url=javascript:alert(1)//{{code}}",
        2,
        "completion.url must be an http:// or https:// URL",
    ),
    case(
        "study-url-data",
        "prg-study",
        "build {turing} --set completion.url=data:text/html,{{code}}",
        2,
        "completion.url must be an http:// or https:// URL",
    ),
    case(
        "study-post-url-ftp",
        "prg-study",
        "build {turing} --set save.post_url=ftp://example.org/in",
        2,
        "save.post_url must be an http:// or https:// URL",
    ),
    case(
        "study-canvas-zero-width",
        "prg-study",
        "build {turing} --set capture.canvas_width=0",
        2,
        "capture.canvas_width must be an integer from",
    ),
    case(
        "study-canvas-zero-height",
        "prg-study",
        "build {turing} --set capture.canvas_height=0",
        2,
        "capture.canvas_height must be an integer from",
    ),
    case(
        "study-render-zero-height",
        "prg-study",
        "build {turing} --set render.height_px=0",
        2,
        "render.height_px must be an integer from 1 to",
    ),
    case("study-nan-alpha", "prg-study", "build {turing} --set alpha=.nan", 2, "alpha must be"),
    case(
        "study-inf-stroke",
        "prg-study",
        "build {turing} --set render.stroke_px=.inf",
        2,
        "render.stroke_px must be a positive finite number",
    ),
    case(
        "study-nan-canvas",
        "prg-study",
        "build {turing} --set capture.canvas_height=.nan",
        2,
        "capture.canvas_height must be an integer",
    ),
    case(
        "study-inf-analysis-margin",
        "prg-study",
        "build {turing} --set analysis.equivalence_margin=.inf",
        2,
        "analysis: equivalence_margin inf is outside",
    ),
    case(
        "study-huge-participants",
        "prg-study",
        "build {turing} --set participants=1000000000",
        2,
        "participants must be an integer from 1 to 10000",
    ),
    case(
        "study-huge-render",
        "prg-study",
        "build {turing} --set render.width_px=1000000",
        2,
        "render.width_px must be an integer from 1 to 4000",
    ),
    case(
        "study-huge-trial-count",
        "prg-study",
        "build {turing} --set participants=10000 --set words=[aa,ab,ac,ad,ae,af,ag,ah,ai,aj,ba,bb,bc,bd,be,bf,bg,bh,bi,bj]",
        2,
        "is 210000 trials; at most 200000",
    ),
    case(
        "study-unknown-setting",
        "prg-study",
        "build {turing} --set completion.colour=red",
        2,
        "completion: unknown key 'colour'",
    ),
    case(
        "study-simulate-huge",
        "prg-study",
        "simulate turing --participants 1000000000 --true-rate 0.2 --out {tmp}/s.csv",
        2,
        "is 11000000000 rows; at most 1000000",
    ),
    case(
        "study-simulate-huge-words",
        "prg-study",
        "simulate turing --participants 3 --words 100000000 --true-rate 0.2 --out {tmp}/s.csv",
        2,
        "--words 100000000: give 2 to 1000 words",
    ),
    case(
        "study-simulate-negative-seed",
        "prg-study",
        "simulate turing --participants 3 --true-rate 0.2 --seed -5 --out {tmp}/s.csv",
        2,
        "argument --seed: -5 must be 0 or more",
    ),
    case(
        "study-power-nan-difference",
        "prg-study",
        "power readability --difference nan",
        2,
        "argument --difference: nan is outside (-1, 1)",
    ),
]

# Arguments every run of a command gets first (a case's own arguments come after and win).
COMMON = {
    "prg-prepare": ["data.augment.per_class=3", "workers=1", "progress=false", "figures=false"],
    "prg-train": ["paths.data_dir={data}", "trainer.max_epochs=1", "trainer.limit_train_batches=1"],
    "prg-evaluate": ["progress=false", "families=[cvae]", "models_dir={tmp}/models"],
    "prg-write": ["mlflow=false", "ckpt={ckpt}"],
    "prg-dictaphone": ["mlflow=false", "ckpt={ckpt}"],
    "prg-simulate": ["mlflow=false", "record=false", "progress=false", "ckpt={ckpt}"],
    "prg-export": ["progress=false"],
    "prg-study": [],
}


def test_the_table_covers_every_command_and_kind_of_input():
    assert len(CASES) >= 30 and len({c.id for c in CASES}) == len(CASES)
    commands = {c.command for c in CASES}
    assert commands == {*HYDRA_COMMANDS, "prg-study"}
    assert {c.code for c in CASES} == {1, 2}


# ---- bad files --------------------------------------------------------------------------------
def _png_header_only(path: Path, width: int, height: int) -> None:
    """A PNG whose header claims ``width`` x ``height`` grey pixels (no pixel data)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IEND", b""))


def _wav(path: Path, samples: np.ndarray) -> None:
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1), f.setsampwidth(2), f.setframerate(16000)
        f.writeframes(samples.astype(np.int16).tobytes())


def bad_files(tmp: Path, checkpoint: Path) -> dict[str, Path]:
    """The table's placeholders (but ``{tmp}``, each test's own folder), made under ``tmp``."""
    from PIL import Image

    from prg.sim import font_word

    rng = np.random.default_rng(0)
    files = {"ckpt": checkpoint, "data": tmp / "data", "turing": REPO / "conf/study/turing.yaml"}
    files["file"] = tmp / "a-file.txt"
    files["file"].write_text("a file, not a folder\n")
    files["folder"] = tmp / "a-folder"
    files["folder"].mkdir()
    files["text_ckpt"] = tmp / "notes.ckpt"
    files["text_ckpt"].write_text("not a checkpoint\n")
    files["truncated_ckpt"] = tmp / "truncated.ckpt"
    whole = checkpoint.read_bytes()
    files["truncated_ckpt"].write_bytes(whole[: len(whole) // 2])
    manifest = tmp / "data/prepared/synthetic/manifest.json"  # what prg-train reads first
    manifest.parent.mkdir(parents=True)
    manifest.write_text('{"source": "synthetic"}\n')
    files["garbage"] = tmp / "garbage.txt"
    files["garbage"].write_bytes(rng.integers(0, 256, 4000, dtype=np.uint8).tobytes())
    files["corrupt_wav"] = tmp / "corrupt.wav"
    files["corrupt_wav"].write_bytes(b"RIFF\x24\x00\x00\x00WAVEfmt " + rng.bytes(64))
    files["silent_wav"] = tmp / "silent.wav"
    _wav(files["silent_wav"], np.zeros(16000))
    files["empty_wav"] = tmp / "empty.wav"
    _wav(files["empty_wav"], np.zeros(0))
    files["text_png"] = tmp / "letters.png"
    files["text_png"].write_text("c a t\n")
    files["blank_png"] = tmp / "blank.png"
    Image.new("L", (120, 40), 255).save(files["blank_png"])
    files["huge_png"] = tmp / "huge.png"
    _png_header_only(files["huge_png"], 40000, 40000)
    files["noise_jpg"] = tmp / "photo.png"  # a JPEG photo of noise under a PNG name
    noise = rng.integers(0, 256, (60, 200, 3), dtype=np.uint8)
    Image.fromarray(noise).save(files["noise_jpg"], format="JPEG")
    files["word"] = font_word("ok").to_json(tmp / "word.json")
    files["bad_json"] = tmp / "bad.json"
    files["bad_json"].write_text("{not json")
    files["bad_yaml"] = tmp / "bad.yaml"
    files["bad_yaml"].write_text("name: [turing\nkind: {\n")
    files["bad_csv"] = tmp / "responses.csv"
    files["bad_csv"].write_bytes(b'participant,"word\n\x00\x01,"x\n')
    files.update(bad_datasets(tmp))
    files["uji_overflow"] = tmp / "overflow.txt"
    files["uji_overflow"].write_text(
        "WORD a trn_UJI_W01-01\nNUMSTROKES 1\nPOINTS 2 # 1 2 99999999999999999999 4\n"
    )
    slow = json.loads(files["word"].read_text())
    slow["dmp"]["tau"] = slow["duration_s"] = 3600.0  # an hour of writing
    files["slow_word"] = tmp / "slow-word.json"
    files["slow_word"].write_text(json.dumps(slow))
    no_dmp = json.loads(files["word"].read_text())
    no_dmp["dmp"] = None
    files["no_dmp_word"] = tmp / "no-dmp-word.json"
    files["no_dmp_word"].write_text(json.dumps(no_dmp))
    files["long_wav"] = tmp / "long.wav"  # 40 s: longer than speech.max_seconds (30 s)
    _wav(files["long_wav"], np.zeros(40 * 16000))
    return files


def _dataset(data_dir: Path, n_points: int = 100, size: int = 28, n_val: int = 4) -> Path:
    """A prepared dataset of a few random samples per split, as prg-prepare writes it."""
    from prg.data.store import save_split

    folder = data_dir / "prepared/synthetic"
    folder.mkdir(parents=True)
    rng = np.random.default_rng(0)
    for split, n in (("train", 8), ("val", n_val), ("test", 4)):
        arrays = {
            "traj": rng.normal(0, 0.5, (n, 2 * n_points)).astype(np.float32),
            "image": rng.integers(0, 256, (n, size, size), dtype=np.uint8),
            "label": np.arange(n, dtype=np.int64),
            "writer": np.array([f"w{split}"] * n),
            "augmented": np.zeros(n, dtype=bool),
            "parent": np.full(n, -1, dtype=np.int64),
        }
        save_split(folder / f"{split}.npz", arrays)
    (folder / "manifest.json").write_text('{"source": "synthetic"}\n')
    return data_dir


def bad_datasets(tmp: Path) -> dict[str, Path]:
    """Prepared datasets the models cannot take, and dataset folders with a broken manifest."""
    found = {
        "points50": _dataset(tmp / "points50", n_points=50),
        "size20": _dataset(tmp / "size20", size=20),
        "no_val": _dataset(tmp / "no-val", n_val=0),
    }
    for name, text in (("cut_manifest", '{"source": "synth'), ("list_manifest", "[1, 2]")):
        found[name] = tmp / name
        (found[name] / "prepared/synthetic").mkdir(parents=True)
        (found[name] / "prepared/synthetic/manifest.json").write_text(text)
    return found


@pytest.fixture(scope="module")
def shared(tmp_path_factory, untrained_muse_checkpoint) -> tuple[Path, dict[str, Path]]:
    """The bad files, made once: their folder and the placeholders."""
    folder = tmp_path_factory.mktemp("bad-files")
    return folder, bad_files(folder, untrained_muse_checkpoint)


# ---- running a command in this process ---------------------------------------------------------
def entry_point(command: str):
    """The function the installed console script ``command`` calls."""
    (point,) = importlib.metadata.entry_points(group="console_scripts", name=command)
    return point.load()


@pytest.fixture
def restore_logging():
    """Hydra configures the root logger for each run; put it back as it was."""
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    yield
    for handler in root.handlers:
        if handler not in handlers:
            handler.close()
    root.handlers[:] = handlers
    root.setLevel(level)


def argv_of(c: Case, files: dict[str, Path], tmp: Path) -> list[str]:
    """The command line of case ``c`` run in the folder ``tmp``."""
    args = [*COMMON[c.command], *c.args]
    if c.command in HYDRA_COMMANDS:
        args = [f"paths.root_dir={tmp}", f"paths.log_dir={tmp / LOGS}", *args]
    return [a.format(tmp=tmp, **files) for a in args]


LOGS = "hydra-logs"  # Hydra's own run folders: the one thing a failed command may leave


def snapshot(*folders: Path) -> dict[Path, tuple[int, int]]:
    """Every file under ``folders`` (but Hydra's ``LOGS``) with its size and mtime. Folders are
    left out: a staging folder made and removed changes its parent's mtime, and an empty
    download cache folder (``data/raw/uji``) is no partial output."""
    found = {}
    for folder in folders:
        for dirpath, dirnames, filenames in os.walk(folder):
            dirnames[:] = [d for d in dirnames if d != LOGS]
            for name in filenames:
                stat = Path(dirpath, name).lstat()
                found[Path(dirpath, name)] = (stat.st_size, stat.st_mtime_ns)
    return found


def check_result(c: Case, code, out: str, err: str) -> None:
    assert "Traceback" not in out + err, err[-3000:]
    lines = err.strip().splitlines()
    assert len(lines) == 1, err[-3000:]
    assert lines[0].startswith(f"{c.command}: error: "), lines[0]
    assert c.expected in lines[0], lines[0]
    assert code == c.code, (code, lines[0])


@pytest.mark.parametrize("c", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_one_line_with_its_exit_code_and_writes_nothing(
    c, tmp_path, shared, monkeypatch, capfd, restore_logging
):
    folder, files = shared
    monkeypatch.chdir(tmp_path)  # default (relative) outputs land where the snapshot looks
    before = snapshot(tmp_path, folder)
    monkeypatch.setattr(sys, "argv", [c.command, *argv_of(c, files, tmp_path)])
    capfd.readouterr()
    try:
        code = entry_point(c.command)()
    except SystemExit as exit:
        code = exit.code
    out, err = capfd.readouterr()
    check_result(c, code, out, err)
    assert snapshot(tmp_path, folder) == before


SUBPROCESS = ["simulate-word-too-large", "study-build-out-below-file"]  # one per kind of CLI


@pytest.mark.parametrize("id", SUBPROCESS)
def test_console_scripts_behave_the_same(id, tmp_path, shared):
    (c,) = [c for c in CASES if c.id == id]
    folder, files = shared
    before = snapshot(tmp_path, folder)
    result = run_cli(c.command, *argv_of(c, files, tmp_path), cwd=tmp_path)
    check_result(c, result.returncode, result.stdout, result.stderr)
    assert snapshot(tmp_path, folder) == before


def _write_to_a_full_disk(cfg) -> None:
    Path("/dev/full").write_text("a result")  # the kernel's always-full device: ENOSPC


def _a_bug(cfg) -> None:
    {}["missing"]  # a programming error, not bad input


@pytest.mark.parametrize(
    "task, one_line", [(_write_to_a_full_disk, True), (_a_bug, False)], ids=["disk-full", "bug"]
)
def test_a_full_disk_is_one_line_exit_1_but_a_bug_keeps_its_traceback(
    task, one_line, tmp_path, monkeypatch, capfd, restore_logging
):
    from prg.commands.cli import hydra_command

    main = hydra_command(task, "prepare", "prg-x")
    monkeypatch.setattr(sys, "argv", ["prg-x", f"paths.root_dir={tmp_path}"])
    capfd.readouterr()
    with pytest.raises(SystemExit) as exit:
        main()
    err = capfd.readouterr().err
    assert exit.value.code == 1
    if one_line:
        assert err.strip().splitlines() == [
            "prg-x: error: No space left on device (free space on that disk, or write elsewhere)"
        ]
    else:
        assert "Traceback" in err and "KeyError: 'missing'" in err
