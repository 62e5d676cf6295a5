"""The layering the code keeps: commands apart from the library and from each other, one home for
atomic renames, and no library module that reaches up into the command layer."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.conftest import REPO

SRC = REPO / "src" / "prg"
COMMANDS = SRC / "commands"
SHARED = {"cli", "settings", "entry"}  # the command layer's plumbing, not commands


def imported_modules(path: Path) -> set[str]:
    """Every module ``path`` imports, at any depth (function-level imports included)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names |= {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def test_no_command_imports_another_command():
    # a command is a module commands/<name>.py or a package commands/<name>/
    packages = {p.parent.name for p in COMMANDS.glob("*/__init__.py")}
    commands = ({p.stem for p in COMMANDS.glob("*.py")} | packages) - SHARED - {"__init__"}
    assert {"write", "dictaphone", "simulate", "train", "evaluate", "prepare"} <= commands
    assert "paper_scale" in packages
    for path in COMMANDS.rglob("*.py"):
        own = path.relative_to(COMMANDS).parts[0].removesuffix(".py")
        others = {f"prg.commands.{c}" for c in commands - {own}}
        prefixes = tuple(f"{o}." for o in others)  # a package command's modules too
        reached = {m for m in imported_modules(path) if m in others or m.startswith(prefixes)}
        assert not reached, (
            f"{path.relative_to(COMMANDS)} imports another command: {sorted(reached)}"
        )


def test_the_library_does_not_import_the_command_layer():
    for path in SRC.rglob("*.py"):
        if COMMANDS in path.parents:
            continue
        reaching_up = {m for m in imported_modules(path) if m.startswith("prg.commands")}
        assert not reaching_up, f"{path.relative_to(SRC)} imports {sorted(reaching_up)}"


def test_atomic_renames_have_one_home():
    for root in (SRC, REPO / "studies"):
        for path in root.rglob("*.py"):
            if path == SRC / "files.py":
                continue
            tree = ast.parse(path.read_text(), str(path))
            calls = [
                node
                for node in ast.walk(tree)
                if isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr in ("replace", "rename")
                and isinstance(node.func.value, ast.Name)
                and node.func.value.id == "os"
            ]
            assert not calls, f"{path} renames files itself: use prg.files"
