"""One place for the accepted range of every numeric option of the ``prg-*`` commands.

Hydra types a value by its look (``3`` int, ``nan``/``inf`` float, ``true`` bool) and checks
nothing else, so ``generate.temperature=nan`` or ``data.splits.val=0`` would reach the
arithmetic. :data:`RANGES` maps each numeric option (dotted key; ``*`` matches one level) to the
values it accepts, and :func:`check_values`, called first by every command's task, refuses a
value outside them with one line naming the option and what is accepted. NaN and infinity are
refused everywhere. ``tests/cli/test_bad_inputs.py`` checks that every numeric option of the composed
configs has an entry here, so a new option cannot skip the check.

Each range is written once. An option read into a settings dataclass takes its range from the
field's declaration (:func:`prg.fields.ranged`): :data:`DECLARED` names the config node and its
class (``generate``: ``prg.pipeline.settings.GenerateSettings``), and :data:`RANGES` is built on
first use from those classes' declared fields (``generate.seed`` ...) and :data:`TABLE`, the
options with no declaring settings class behind them (data, model, trainer ...) and those a
class checks against a named constant here (a top-level key read by several commands, an option
holding several numbers, checked item by item). The declaring settings modules import no numpy,
so the check still runs before any heavy library is loaded.

:data:`CHOICES` holds the options that name one of a fixed set (``family``: :data:`FAMILIES`;
``generate.method``: the constant :data:`DECLARED_CHOICES` names, built on first use like
:data:`RANGES`), checked by :func:`check_values` too, and :func:`unknown_key` is the line for an
option the config does not have (with the closest keys and the keys accepted there). The runner
(:mod:`prg.commands.preflight`) runs these checks on the composed command line before any heavy
library is imported.

:func:`require_number` is the same check for one value (for settings read outside the config);
:func:`literal_text` recovers the characters the user typed for a text option that Hydra typed as
a number or a boolean (``text=true``, ``text=1e3``).
"""

from __future__ import annotations

import difflib
import fnmatch
import functools
import importlib
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from prg.errors import SettingsError, UsageError

SEED_MAX = 2**32 - 1  # numpy's and Lightning's seed range is [0, 2**32 - 1]
MAX_TEXT_LETTERS = 64  # prg-write: letters in one line of text (all written as one DMP)


@dataclass(frozen=True)
class Range:
    """The values a numeric option accepts: an interval, integers only or not, null or not."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    optional: bool = False  # null accepted (the option's "not set")
    also: tuple[int, ...] = ()  # special values accepted outside the interval (-1: no limit)
    text: bool = False  # a string is also accepted (its own code checks it: "auto")

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a finite number"
        if self.low is not None and self.high is not None:
            left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
            text = f"{kind} in {left}{_num(self.low)}, {_num(self.high)}{right}"
        elif self.low is not None:
            text = f"{kind} {'>' if self.low_open else '>='} {_num(self.low)}"
        elif self.high is not None:
            text = f"{kind} {'<' if self.high_open else '<='} {_num(self.high)}"
        else:
            text = kind
        extra = [str(v) for v in self.also] + (["null"] if self.optional else [])
        extra += ["a name"] if self.text else []
        return text + "".join(f" or {e}" for e in extra)

    def accepts(self, value: Any) -> bool:
        if value is None:
            return self.optional
        if self.text and isinstance(value, str):
            return True
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        if value in self.also:
            return True
        if self.integer and not isinstance(value, int):
            return False
        if not math.isfinite(value):
            return False
        above = self.low is None or (value > self.low if self.low_open else value >= self.low)
        below = self.high is None or (value < self.high if self.high_open else value <= self.high)
        return above and below


def _num(x: float) -> str:
    return f"{int(x):,}" if float(x).is_integer() and abs(x) >= 10_000 else f"{x:g}"


def positive(high: float | None = None) -> Range:
    return Range(0, high, low_open=True)


def non_negative(high: float | None = None) -> Range:
    return Range(0, high)


def count(low: int = 1, high: int | None = None, **kw: Any) -> Range:
    return Range(low, high, integer=True, **kw)


SEED = count(0, SEED_MAX)
FRACTION = Range(0, 1, low_open=True, high_open=True)  # strictly between 0 and 1
PROBABILITY = Range(0, 1)
METRES = Range(-10, 10)  # positions in the simulated scene (and joint angles, in radians)
DEGREES = Range(-360, 360)
WEIGHT_MAX = 1e6  # loss and cost weights
TEMPERATURE_MAX = 10.0  # latents drawn with their std times this: 1 is the model's own spread
TEMPERATURE = non_negative(TEMPERATURE_MAX)
ALPHA_MAX_DEG = Range(0, 180, low_open=True)  # connection.alpha_max_deg: a turn per step

IMAGE_SHIFT = count(0, 8)  # whole pixels of a 28 x 28 image
N_TEST = count(1, optional=True)  # test samples (null: all)

# ---- options of prg-export and prg-simulate whose settings classes use these constants ----
SCALE = positive(1000)  # the word's size relative to its own: prg-simulate, prg-export (plotter)
TEMPO = positive(10)  # multiplies the DMP's duration: prg-simulate, prg-export
WORKSPACE_STEP_CM = positive(100)  # prg-simulate: the reachability grid (SimSettings)
WORD_CENTRE_CM = Range(-1000, 1000)  # paper.word_centre_cm: each coordinate (SimSettings)
SAMPLE_DT_S = Range(0, 0.1, low_open=True)  # prg-export: the G-code's rollout step (s)
PAPER_MM = positive(10_000)  # plotter.paper_mm: each of the sheet's two sizes
POSITION_MM = Range(-10_000, 10_000, optional=True)  # plotter.position_mm: each coordinate
ORIGIN_MM = Range(-10_000, 10_000)  # gcode.origin_mm: each coordinate

# ---- the config nodes whose ranges their settings class declares (prg.fields.ranged) ----
DECLARED: dict[str, tuple[str, str]] = {  # config node -> (module, settings class)
    "generate": ("prg.pipeline.settings", "GenerateSettings"),
    "marks": ("prg.pipeline.settings", "MarkSettings"),
    "likelihood": ("prg.evaluation.settings", "LikelihoodSettings"),
    "coherence": ("prg.evaluation.settings", "CoherenceSettings"),
    "classifier": ("prg.evaluation.settings", "ClassifierSettings"),
    "likeness": ("prg.evaluation.settings", "LikenessSettings"),
    "styles": ("prg.evaluation.settings", "StyleSettings"),
    "layout": ("prg.pipeline.settings", "LayoutSettings"),
    "connection": ("prg.pipeline.settings", "ConnectionSettings"),
    "gcode": ("prg.export.settings", "GcodeSettings"),
    "hpgl": ("prg.export.settings", "HpglSettings"),
    "limits": ("prg.export.settings", "LimitSettings"),
    "paper": ("prg.sim.settings", "Paper"),
    "motion": ("prg.sim.settings", "MotionSettings"),
    "control": ("prg.sim.settings", "ControlSettings"),
    "ik": ("prg.sim.settings", "IKSettings"),
    "camera": ("prg.sim.settings", "Camera"),
    "robot": ("prg.sim.settings", "RobotSettings"),
}

# ---- every other numeric option of conf/ (prepare, train, evaluate, write, dictaphone, ...) ----
TABLE: dict[str, Range] = {
    # data (prg-prepare; read back by prg-train and prg-evaluate)
    "data.seed": SEED,
    "data.preprocess.n_points": count(2, 4096),
    "data.preprocess.smooth_sigma": non_negative(100),
    "data.image.size": count(4, 1024),
    "data.image.stroke_width": positive(100),
    "data.image.margin": non_negative(100),
    "data.augment.per_class": count(0, 100_000),
    "data.augment.snr_target_db": Range(0, 500),
    "data.augment.max_components": count(1, 100),
    "data.augment.amplitude": Range(0, 1, high_open=True),
    "data.augment.rotation_deg": non_negative(180),
    "data.augment.sweep": PROBABILITY,
    "data.splits.*": FRACTION,  # each split needs writers: train, validation, test
    "data.loader.batch_size": count(1),
    "data.loader.num_workers": count(0, 256),
    "data.synthetic.n_writers": count(1, 10_000),
    "data.synthetic.samples_per_char": count(1, 1000),
    "data.synthetic.slant": Range(-10, 10),
    "data.synthetic.width": positive(10),
    "data.synthetic.size": positive(10),
    "data.synthetic.rotation_deg": Range(-180, 180),
    "data.synthetic.roundness": non_negative(100),
    "data.synthetic.jitter": non_negative(1),
    "data.synthetic.sample_variation": non_negative(1),
    "data.synthetic.points_per_unit": positive(1000),
    "workers": count(1, 256),
    "threads": count(1, 256),
    # prg-train
    "seed": SEED,
    "model.batch_size": count(1),
    "model.module.model.latent_dim": count(1, 4096),
    "model.module.model.top_latent_dim": count(1, 4096),
    "model.module.model.traj_std": positive(100),
    "model.module.model.alpha": non_negative(WEIGHT_MAX),
    "model.module.model.beta": non_negative(WEIGHT_MAX),
    "model.module.model.delta": non_negative(WEIGHT_MAX),
    "model.module.model.mode_seeking": non_negative(WEIGHT_MAX),
    "model.module.model.mode_bank": count(0, 4096),
    "model.module.model.kl_weight": non_negative(WEIGHT_MAX),
    "model.module.model.lambdas.*": non_negative(WEIGHT_MAX),
    "model.module.model.alphas.*": non_negative(WEIGHT_MAX),
    "model.module.model.gammas.*": non_negative(WEIGHT_MAX),
    "model.module.optimizer.lr": positive(10),
    "model.module.optimizer.weight_decay": non_negative(10),
    "model.module.optimizer.betas": Range(0, 1, high_open=True),
    "model.module.optimizer.eps": positive(1),
    "model.module.optimizer.momentum": Range(0, 1, high_open=True),
    "model.module.scheduler.max_lr": positive(10),
    "model.module.scheduler.pct_start": FRACTION,
    "model.module.kl_warmup_epochs": count(0),
    "model.module.image_shift": IMAGE_SHIFT,
    "trainer.max_epochs": count(1, also=(-1,)),
    "trainer.max_steps": count(1, also=(-1,)),
    "trainer.limit_train_batches": positive(),  # a fraction (<= 1.0) or a number of batches
    "trainer.limit_val_batches": positive(),
    "trainer.check_val_every_n_epoch": count(1, optional=True),
    "trainer.log_every_n_steps": count(1),
    "trainer.devices": count(0, also=(-1,), text=True),  # a count, "auto", or device ids
    "trainer.num_nodes": count(1),
    "callbacks.checkpoint.save_top_k": count(0, also=(-1,)),
    "callbacks.last.every_n_train_steps": count(0),
    "callbacks.figures.every_n_epochs": count(1),
    "callbacks.figures.n_examples": count(1, 64),
    "callbacks.early_stopping.patience": count(0),
    "callbacks.early_stopping.min_delta": non_negative(),  # a loss difference: any finite size
    "callbacks.early_stopping.start_fraction": PROBABILITY,
    "callbacks.system_metrics.sampling_interval_s": positive(),
    "quick_epochs.*": count(1),
    "converged_epochs.*": count(1),
    # prg-evaluate (its settings classes declare the rest; these options hold several numbers,
    # which the classes check item by item)
    "n_test": N_TEST,  # top level, as seed: EvaluationSettings declares both with these ranges
    "coherence.temperatures.*": TEMPERATURE,
    "coherence.image_shifts": IMAGE_SHIFT,
    "styles.ks": count(1, 61),  # letters given as the style (the other classes are scored)
    "styles.seeds": SEED,
    # prg-write (and prg-dictaphone, prg-simulate, which run it)
    # ConnectionSettings holds this turn as alpha_max, in radians: it checks it against this
    # range, converted, and declares no range of its own for an option the config does not have
    "connection.alpha_max_deg": ALPHA_MAX_DEG,
    "speech.max_seconds": positive(600),
    "speech.min_rms_dbfs": Range(-200, 0),
    "speech.beam_size": count(1, 64),
    "speech.prior_weight": Range(0, 1),
    "speech.slowdown": Range(1, 2),
    "speech.view_margin": non_negative(1000),  # nats; 1000: always both views
    "speech.min_lead": non_negative(1000),  # nats
    "speech.noise_subtraction": Range(0, 10),
    # prg-dictaphone
    "speed": Range(10, 1000),  # espeak-ng words per minute
    # prg-simulate (its settings classes declare the rest; SimSettings declares these with
    # these constants: top-level keys, as seed, and the word's centre, given under paper)
    "scale": SCALE,
    "tempo": TEMPO,
    "workspace_step_cm": WORKSPACE_STEP_CM,
    "paper.word_centre_cm": WORD_CENTRE_CM,
    # prg-export (its settings classes declare the rest; ExportSettings declares sample_dt_s and
    # tempo, PlotterSettings checks scale, with these constants: top-level keys, as seed; and
    # the options holding two numbers, which the classes check item by item: PlotterSettings
    # declares no range, so plotter is not in DECLARED)
    "sample_dt_s": SAMPLE_DT_S,
    "plotter.paper_mm": PAPER_MM,
    "plotter.position_mm": POSITION_MM,
    "gcode.origin_mm": ORIGIN_MM,
    "limits.joints.*.lower": DEGREES,  # rad
    "limits.joints.*.upper": DEGREES,
    "limits.joints.*.velocity": positive(1000),  # rad/s
    "limits.joints.*.acceleration": positive(1e5),  # rad/s^2
    "limits.joints.*.jerk": positive(1e7),  # rad/s^3
}


# ---- options that name one of a fixed set ----
# the model families, conf/model/<family>.yaml: the paper's four (the demo's, and the default of
# make paper / make converged), then the baselines
PAPER_FAMILIES = ("cvae", "avae_ts", "avae_ti", "muse")
FAMILIES = (*PAPER_FAMILIES, "mvae", "mmvae", "mopoe")
TABLE_CHOICES: dict[str, tuple[str, tuple[str, ...]]] = {  # key -> (what a value is, accepted)
    "family": ("family", FAMILIES),  # prg-write, prg-dictaphone, prg-simulate
    "families": ("family", FAMILIES),  # prg-evaluate (a list)
    "resume": ("resume mode", ("sweep", "auto", "never")),  # prg-train (prg.commands.train)
}
DECLARED_CHOICES: dict[str, tuple[str, str, str]] = {  # key -> (what, module, its constant)
    "generate.mode": ("decoding mode", "prg.pipeline.settings", "DECODING_MODES"),
    "generate.method": ("connection method", "prg.pipeline.settings", "CONNECTION_METHODS"),
    "generate.timing": ("timing", "prg.pipeline.settings", "TIMINGS"),
}  # speech.backend is checked by its task: importing prg.pipeline.speech loads numpy


@functools.cache
def _choices() -> dict[str, tuple[str, tuple[str, ...]]]:
    declared = {
        key: (what, tuple(getattr(importlib.import_module(module), name)))
        for key, (what, module, name) in DECLARED_CHOICES.items()
    }
    return TABLE_CHOICES | declared


@functools.cache
def _ranges() -> dict[str, Range]:
    from prg.fields import declared_ranges

    declared: dict[str, Range] = {}
    for node, (module, name) in DECLARED.items():
        declared |= declared_ranges(getattr(importlib.import_module(module), name), node)
    return declared | TABLE


def __getattr__(name: str) -> Any:
    if name == "RANGES":  # built on first use: the settings modules import this one
        return _ranges()
    if name == "CHOICES":  # the same
        return _choices()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def range_of(key: str) -> Range | None:
    """The entry of :data:`RANGES` for the dotted ``key`` (exact first, then patterns)."""
    ranges = _ranges()
    if key in ranges:
        return ranges[key]
    depth = key.count(".")
    for pattern, spec in ranges.items():
        if pattern.count(".") == depth and fnmatch.fnmatchcase(key, pattern):
            return spec
    return None


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def require_number(value: Any, key: str, spec: Range) -> Any:
    """``value`` if ``spec`` accepts it, else :class:`~prg.errors.SettingsError` naming ``key``
    (a config key, or a settings field that the command layer prefixes) and the range."""
    if not spec.accepts(value):
        raise SettingsError(key, f"must be {spec.describe()}, got {_short(value)}")
    return value


def leaves(node: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(dotted key, value) of every leaf of a plain nested mapping; lists are leaves."""
    for name, value in node.items():
        key = f"{prefix}{name}"
        if isinstance(value, Mapping):
            yield from leaves(value, key + ".")
        else:
            yield key, value


def _plain(cfg: Any) -> Any:
    from omegaconf import DictConfig, OmegaConf
    from omegaconf.errors import OmegaConfBaseException

    if not isinstance(cfg, DictConfig):
        return cfg
    try:
        return OmegaConf.to_container(cfg, resolve=True)
    except OmegaConfBaseException as err:
        raise UsageError(f"the config cannot be resolved: {' '.join(str(err).split())}") from None


# ---- options that name a folder (the prepared dataset's, under <data_dir>/prepared/) ----
FOLDER_NAMES = ("data.name", "data_name", "datamodule.name")


def folder_name_problem(value: Any) -> str | None:
    """Why ``value`` cannot be a plain folder name (None when it can): empty, not text, a
    ``/``, a leading ``.``, a control character (a newline, a tab) or over 255 bytes."""
    if not isinstance(value, str) or not value:
        return "is not a folder name"
    if "/" in value or value.startswith("."):
        return "is a path, not a plain folder name"
    if not value.isprintable():
        return "holds a control character (a newline, a tab ...)"
    if len(value.encode("utf-8", "surrogateescape")) > 255:
        return "is longer than 255 bytes"
    return None


def check_folder_name(value: Any, key: str) -> str:
    """``value`` if it is a plain folder name (:func:`folder_name_problem`), else one line
    naming ``key`` and what is accepted."""
    problem = folder_name_problem(value)
    if problem:
        raise UsageError(
            f"{key}={value!r} {problem}: accepted are printable characters without '/', not "
            "starting with '.', at most 255 bytes"
        )
    return value


def check_values(cfg: Any) -> None:
    """Refuse the first numeric option of ``cfg`` (DictConfig or mapping) outside its range.

    Keys without an entry in :data:`RANGES` are not checked here (their own code checks them);
    list values are checked element by element (``paper.size_cm=[0,29.7]``). The options of
    :data:`CHOICES` must name one of their accepted values, those of :data:`FOLDER_NAMES` a
    plain folder name.
    """
    choices = _choices()
    for key, value in leaves(_plain(cfg)):
        if key in choices:
            check_choice(value, key)
            continue
        if key in FOLDER_NAMES:
            check_folder_name(value, key)
            continue
        spec = range_of(key)
        if spec is None:
            continue
        if isinstance(value, list | tuple):
            for i, item in enumerate(value):
                if not spec.accepts(item) or item is None:
                    raise UsageError(
                        f"{key}[{i}] must be {spec.describe()}, got {_short(item)} "
                        f"(in {key}={_short(value)})"
                    )
        else:
            require_number(value, key, spec)


def check_choice(value: Any, key: str) -> None:
    """Refuse a value of the option ``key`` (:data:`CHOICES`; each item of a list) that is not
    one of its accepted values: ``unknown family musee; accepted: cvae, avae_ts, avae_ti, muse``."""
    what, accepted = _choices()[key]
    for item in value if isinstance(value, list | tuple) else [value]:
        if item not in accepted:
            where = f" in {key}={_short(value)}" if isinstance(value, list | tuple) else ""
            raise UsageError(f"unknown {what} {item}{where}; accepted: {', '.join(accepted)}")


def _keys(node: Mapping, prefix: str = "") -> Iterator[str]:
    """Every dotted key of a plain nested mapping, the mappings' own keys included."""
    for name, value in node.items():
        yield f"{prefix}{name}"
        if isinstance(value, Mapping):
            yield from _keys(value, f"{prefix}{name}.")


def _closest(key: str, known: Iterable[str], cutoff: float = 0.75) -> list[str]:
    """Up to three of ``known`` most like ``key``, as a whole or by their last part
    (``temperature`` -> ``generate.temperature``)."""

    def likeness(other: str) -> float:
        whole = difflib.SequenceMatcher(None, key, other).ratio()
        last = difflib.SequenceMatcher(None, key.rpartition(".")[2], other.rpartition(".")[2])
        return max(whole, last.ratio())

    scored = sorted(((likeness(k), k) for k in known), key=lambda s: -s[0])
    return [k for score, k in scored[:3] if score >= cutoff]


def unknown_key(key: str, config: Mapping) -> str:
    """The line for an option ``key`` that ``config`` (a plain nested mapping: the composed
    config) does not have: the closest existing keys and the keys accepted where it was given.

    ``unknown key txt (closest: text); accepted top-level keys: text, on_unknown, ...``
    """
    parent, _, _ = key.rpartition(".")
    node: Any = config
    for part in parent.split(".") if parent else []:
        node = node.get(part) if isinstance(node, Mapping) else None
    closest = _closest(key, _keys(config))
    line = f"unknown key {key}"
    if closest:
        line += f" (closest: {', '.join(closest)})"
    if not isinstance(node, Mapping):
        return f"{line}; {parent} takes a value, not keys"
    where = f"under {parent}" if parent else "top-level keys"
    return f"{line}; accepted {where}: {', '.join(map(str, node))}"


def _typed_override(key: str) -> str | None:
    """The characters after ``key=`` on the command line (Hydra's task overrides), if any."""
    try:
        from hydra.core.hydra_config import HydraConfig

        if not HydraConfig.initialized():
            return None
        overrides = list(HydraConfig.get().overrides.task)
    except Exception:  # no Hydra run: the value came from a config file or a caller
        return None
    for line in reversed(overrides):
        name, sep, value = line.partition("=")
        if sep and name.lstrip("+~") == key:
            return value
    return None


def literal_text(value: Any, key: str) -> str | None:
    """The text option ``key`` as the characters the user typed.

    Hydra reads ``text=true`` as the boolean True and ``text=1e3`` as the float 1000.0; their
    characters are taken back from the command line. A non-text value from anywhere else is
    refused with the quoting that keeps it text.
    """
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, bool | int | float):
        typed = _typed_override(key)
        if typed is not None:
            return typed
        kind = "boolean" if isinstance(value, bool) else "number"
    else:
        kind = type(value).__name__
    raise UsageError(
        f"{key}={_short(value)} was read as a {kind}, not text: quote it, {key}=\"'...'\""
    )


def literal_words(values: Any, key: str) -> list[str]:
    """A list option of words (``words``, ``speech.lexicon``); every item must be text."""
    words = list(values)
    for i, item in enumerate(words):
        if not isinstance(item, str):
            kind = "a boolean" if isinstance(item, bool) else "a number"
            if not isinstance(item, bool | int | float):
                kind = f"a {type(item).__name__}"
            raise UsageError(
                f"{key}[{i}]={_short(item)} was read as {kind}, not a word: quote each word as "
                f"typed, {key}=\"['...', '...']\""
            )
    return words


def check_text_length(text: str, key: str = "text") -> str:
    """``text`` if it holds at most :data:`MAX_TEXT_LETTERS` letters (the line is one DMP whose
    fit grows with the square of its length)."""
    letters = sum(not c.isspace() for c in text)
    if letters > MAX_TEXT_LETTERS:
        raise UsageError(
            f"{key} has {letters} letters: accepted are at most {MAX_TEXT_LETTERS} per line "
            "(write a longer text in several runs)"
        )
    return text
