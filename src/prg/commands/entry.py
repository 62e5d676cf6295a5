"""The console scripts (``[project.scripts]`` in ``pyproject.toml``): each ``prg-*`` command's
``main``, made without importing the module of its task, so that ``--help`` and a bad command
line are answered before torch, Lightning or MLflow are imported: :func:`hydra_command` imports
``prg.commands.<name>`` once the command line has been checked and the task starts.
``python -m prg.commands.<name>`` runs the same ``main``.
"""

from __future__ import annotations

from prg.commands.cli import hydra_command

prepare = hydra_command("prg.commands.prepare:prepare", "prepare", "prg-prepare")
train = hydra_command("prg.commands.train:train", "train", "prg-train")
evaluate = hydra_command("prg.commands.evaluate:evaluate", "evaluate", "prg-evaluate")
write = hydra_command("prg.commands.write:write", "write", "prg-write", fast_exit=True)
dictaphone = hydra_command("prg.commands.dictaphone:dictaphone", "dictaphone", "prg-dictaphone")
simulate = hydra_command("prg.commands.simulate:simulate", "simulate", "prg-simulate")
export = hydra_command("prg.commands.export:export", "export", "prg-export")
