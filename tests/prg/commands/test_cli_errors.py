"""One line, with what to do, for the machine's errors: a full or read-only disk (OSError) and an
MLflow store that refuses writes (real SQLite errors); folder names with control characters."""

from __future__ import annotations

import errno
import sqlite3

import pytest
from omegaconf import OmegaConf

from prg.checks import check_folder_name, check_values
from prg.commands.cli import os_error_message, store_error_message
from prg.data.build import DataSettings
from prg.errors import SettingsError, UsageError


@pytest.mark.parametrize(
    "err, expected",
    [
        (
            OSError(errno.ENOSPC, "No space left on device", "/data/m.json"),
            "/data/m.json: No space left on device (free space on that disk, or write elsewhere)",
        ),
        (
            OSError(errno.ENOSPC, "No space left on device"),
            "No space left on device (free space on that disk, or write elsewhere)",
        ),
        (
            OSError(errno.EROFS, "Read-only file system", "/ro/x"),
            "/ro/x: Read-only file system (the file system is read-only: write elsewhere)",
        ),
        (OSError(errno.ENOENT, "No such file or directory", "/x"), "/x: No such file or directory"),
    ],
)
def test_os_errors_say_what_to_do(err, expected):
    assert os_error_message(err) == expected


def _readonly_write_error(tmp_path) -> BaseException:
    store = tmp_path / "mlruns.db"
    sqlite3.connect(store).execute("create table runs (id text)").connection.commit()
    readonly = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    try:
        readonly.execute("insert into runs values ('a')")
    except sqlite3.OperationalError as err:
        return err
    raise AssertionError("a read-only database took a write")


def test_a_read_only_store_names_the_store_and_what_to_do(tmp_path):
    cfg = OmegaConf.create(
        {"logger": {"tracking_uri": "sqlite:///s.db"}, "paths": {"root_dir": str(tmp_path)}}
    )
    try:
        raise RuntimeError("logging the run failed") from _readonly_write_error(tmp_path)
    except RuntimeError as wrapped:
        message = store_error_message(wrapped, cfg)
    assert message == (
        "MLflow store sqlite:///s.db is read-only: make it writable, or log elsewhere with "
        "logger.tracking_uri=URI or MLFLOW_TRACKING_URI (mlflow=false: no run)"
    )


def test_other_errors_are_not_store_errors(tmp_path):
    assert store_error_message(KeyError("missing"), OmegaConf.create({})) is None
    assert store_error_message(RuntimeError("readonly database"), OmegaConf.create({})) is None


@pytest.mark.parametrize("name", ["a\nb", "tab\there", "", ".hidden", "a/b", "x" * 256])
def test_a_data_name_that_is_no_plain_folder_name_is_refused(name):
    with pytest.raises(UsageError, match="accepted are printable characters") as refused:
        check_folder_name(name, "data.name")
    assert "\n" not in str(refused.value)
    with pytest.raises(UsageError, match=r"^data\.name="):
        check_values({"data": {"name": name}})
    with pytest.raises(SettingsError, match=r"^name "):
        DataSettings(name=name, source="synthetic")


def test_plain_names_pass():
    assert check_folder_name("synthetic uji-2 é", "data.name") == "synthetic uji-2 é"
    check_values({"data": {"name": "synthetic"}, "data_name": "uji"})
