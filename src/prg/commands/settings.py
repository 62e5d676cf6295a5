"""The command layer's side of the typed configuration boundary: config nodes -> library settings.

Library settings classes validate themselves and name the field they refuse
(:class:`prg.errors.SettingsError`); here each node is read from the composed config and the
error gets the node's path (``generate.speed_cm_s``), so the library does not know the layout of
the config tree. Shared by the commands that write words (``prg-write``, ``prg-dictaphone``,
``prg-simulate``); not a command itself.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from omegaconf import DictConfig, OmegaConf

from prg.checks import literal_words
from prg.commands.cli import describe_root
from prg.errors import SettingsError, UsageError

if TYPE_CHECKING:  # imported where used: a bad command line is answered before numpy and torch
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.speech import SpeechSettings
    from prg.sim import RobotSettings, SimSettings
    from prg.writer import Writer

MAX_LEXICON_BYTES = 1_000_000  # a word list, not a dictionary dump: about 100,000 words


def node(cfg: DictConfig, key: str) -> dict[str, Any]:
    """The config node ``key`` as plain values (interpolations resolved)."""
    return OmegaConf.to_container(cfg[key], resolve=True)


def build(cls: type, values: dict[str, Any], key: str, **extra: Any) -> Any:
    """``cls(**values, **extra)``; a refused field is named under ``key``, an unknown one too."""
    try:
        return cls(**values, **extra)
    except SettingsError as err:
        raise err.under(key) from None
    except TypeError as err:  # an unknown or missing field
        raise UsageError(f"{key} settings: {err}") from None


def generate_settings(cfg: DictConfig) -> GenerateSettings:
    """``generate``, ``layout`` and ``connection`` as :class:`GenerateSettings`."""
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.connect import ConnectionSettings
    from prg.pipeline.layout import LayoutSettings
    from prg.pipeline.marks import MarkSettings

    connection = node(cfg, "connection")
    degrees = connection.pop("alpha_max_deg")
    if isinstance(degrees, bool) or not isinstance(degrees, int | float):
        raise UsageError(f"connection.alpha_max_deg must be a number, got {degrees!r}")
    connection["alpha_max"] = math.radians(degrees)
    delayed = cfg.get("delayed_strokes", True)
    if not isinstance(delayed, bool):
        raise UsageError(f"delayed_strokes must be true or false, got {delayed!r}")
    return build(
        GenerateSettings,
        node(cfg, "generate"),
        "generate",
        delayed_strokes=delayed,
        marks=build(MarkSettings, node(cfg, "marks"), "marks"),
        layout=build(LayoutSettings, node(cfg, "layout"), "layout"),
        connection=build(ConnectionSettings, connection, "connection"),
    )


def read_lexicon(path: Path) -> list[str]:
    """The words of a lexicon file: UTF-8 text, one word (or short phrase) per line."""
    hint = "give a text file with one word per line, or a list: speech.lexicon=[bell,cat]"
    try:
        if path.stat().st_size > MAX_LEXICON_BYTES:
            raise UsageError(
                f"speech.lexicon {path}: {path.stat().st_size:,} bytes; accepted are word lists "
                f"up to {MAX_LEXICON_BYTES:,} bytes"
            )
        text = path.read_bytes().decode("utf-8")
    except OSError as err:
        raise UsageError(
            f"speech.lexicon {path}: not a readable word list ({err.strerror}); {hint}"
        ) from None
    except UnicodeDecodeError as err:
        raise UsageError(
            f"speech.lexicon {path}: not UTF-8 text (byte {err.start}); {hint}"
        ) from None
    if any(ord(c) < 32 and c not in "\t\r\n" for c in text):
        raise UsageError(f"speech.lexicon {path}: holds control characters, not text; {hint}")
    return [w for w in text.splitlines() if w.strip()]


def speech_settings(cfg: DictConfig) -> SpeechSettings:
    """``speech`` as :class:`SpeechSettings`; ``lexicon`` may name a text file of words."""
    from prg.pipeline.speech import SpeechSettings

    settings = node(cfg, "speech")
    lexicon = settings.get("lexicon")
    if isinstance(lexicon, str):
        settings["lexicon"] = read_lexicon(Path(lexicon))
    elif lexicon is not None:
        settings["lexicon"] = literal_words(lexicon, "speech.lexicon")
    return build(SpeechSettings, settings, "speech")


def checkpoint_path(cfg: DictConfig) -> Path:
    """``ckpt``, or the exported model of ``family`` under ``models_dir``; a file that does not
    exist is refused naming its absolute path and how to point elsewhere."""
    if cfg.ckpt:
        path = Path(cfg.ckpt)
        if not path.exists():
            raise UsageError(f"ckpt={cfg.ckpt}: {path.absolute()} does not exist")
        return path
    path = Path(cfg.models_dir) / cfg.family / "model.ckpt"
    if not path.exists():
        raise UsageError(
            f"checkpoint {path.absolute()} does not exist: no {cfg.family} model under "
            f"models_dir ({describe_root(cfg.paths.root_dir)}); give ckpt=FILE, "
            "PRG_ROOT=FOLDER for another project, or train it there (`make demo`)"
        )
    return path


def writer_from_config(cfg: DictConfig) -> Writer:
    """The :class:`~prg.writer.Writer` of a write config: its checkpoint and settings."""
    from prg.writer import Writer

    path = checkpoint_path(cfg)  # before the settings: a missing model is answered first
    generate, speech = generate_settings(cfg), speech_settings(cfg)
    if cfg.get("threads"):
        import torch

        torch.set_num_threads(int(cfg.threads))
    style = cfg.get("style")
    if style is not None and not isinstance(style, str):
        raise UsageError(f"style must be a file path, got {style!r}")
    return Writer.from_checkpoint(
        path, settings=generate, speech=speech, on_unknown=cfg.on_unknown, style=style
    )


def simulation_settings(cfg: DictConfig) -> tuple[RobotSettings, SimSettings]:
    """``robot`` as :class:`~prg.sim.robots.RobotSettings` and the simulation nodes (``paper``,
    ``motion``, ``control``, ``ik``, ``camera``, ``scale``, ``tempo``, ``workspace_step_cm``) as
    :class:`~prg.sim.settings.SimSettings`."""
    from prg.sim import RobotSettings, SimSettings

    try:
        robot = RobotSettings.from_dict(node(cfg, "robot"))
    except SettingsError as err:
        raise err.under("robot") from None
    values = {key: node(cfg, key) for key in ("paper", "motion", "control", "ik", "camera")}
    values |= {key: cfg[key] for key in ("scale", "tempo", "workspace_step_cm")}
    return robot, SimSettings.from_mapping(values)
