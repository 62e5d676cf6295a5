"""Helpers shared by the tests that were split out of tests/test_checkpoint_trust.py."""

from __future__ import annotations

import os

import torch


class _RunsCode:
    """Unpickling this calls ``os.system``: what a hostile checkpoint would do."""

    def __init__(self, command: str):
        self.command = command

    def __reduce__(self):
        return (os.system, (self.command,))


def _hostile_pickle(path, marker) -> None:
    torch.save(
        {"state_dict": {}, "hyper_parameters": {}, "payload": _RunsCode(f"touch {marker}")}, path
    )
