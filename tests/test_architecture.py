"""The layering the code keeps: commands apart from the library and from each other, one home for
atomic renames, no library module that reaches up into the command layer, a test file for every
module, and modules of one concept each."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.conftest import REPO

SRC = REPO / "src" / "prg"
COMMANDS = SRC / "commands"
SHARED = {"cli", "preflight", "settings", "entry"}  # the command layer's plumbing, not commands


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


# Modules without a test file at their mirrored path (src/prg/a/b.py -> tests/prg/a/test_b.py,
# studies/a/b.py -> tests/studies/a/test_b.py), each with where it is tested instead.
UNMIRRORED = {
    "prg.commands.dictaphone": "the command, run through its console script in tests/cli/test_dictaphone.py",
    "prg.commands.entry": "the console-script entry points, run by tests/cli/test_startup.py",
    "prg.commands.export": "the command, run through its console script in tests/cli/test_export.py",
    "prg.commands.paper_scale.command": "tested with its package in tests/prg/commands/test_paper_scale.py",
    "prg.commands.paper_scale.device": "tested with its package in tests/prg/commands/test_paper_scale.py",
    "prg.commands.paper_scale.jobs": "tested with its package in tests/prg/commands/test_paper_scale.py",
    "prg.commands.paper_scale.options": "tested with its package in tests/prg/commands/test_paper_scale.py",
    "prg.commands.simulate": "the command, run through its console script in tests/cli/test_simulate.py",
    "prg.commands.tracking": "the tracking command; run in-process by tests/prg/test_tracking.py",
    "prg.data.figures": "dataset figures, drawn by prg.data.build in tests/prg/data/test_build.py",
    "prg.data.samples": "tested through tests/prg/data/test_uji.py, tests/prg/pipeline/test_hands.py",
    "prg.data.sigma_lognormal.extraction": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.data.sigma_lognormal.fitting": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.data.sigma_lognormal.model": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.data.sigma_lognormal.params": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.data.sigma_lognormal.perturbation": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.data.sigma_lognormal.snr": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.data.sigma_lognormal.timing": "tested with its package in tests/prg/data/test_sigma_lognormal.py",
    "prg.errors": "the error types; every test that expects a refusal uses them",
    "prg.evaluation.dictaphone": "Table II; run through prg-dictaphone in tests/cli/test_dictaphone.py",
    "prg.evaluation.figures": "evaluation figures, drawn by prg.evaluation.run in tests/cli/test_evaluate.py",
    "prg.export.ros": "the ROS format, written by prg.export.run in tests/prg/export/test_run.py",
    "prg.pipeline.dmp.canonical": "tested with its package in tests/prg/pipeline/test_dmp.py",
    "prg.pipeline.dmp.model": "tested with its package in tests/prg/pipeline/test_dmp.py",
    "prg.pipeline.dmp.settings": "tested with its package in tests/prg/pipeline/test_dmp.py",
    "prg.pipeline.dmp.threads": "tested with its package in tests/prg/pipeline/test_dmp.py",
    "prg.pipeline.dmp.validation": "tested with its package in tests/prg/pipeline/test_dmp.py",
    "prg.pipeline.speech.backends.base": "tested with its package in tests/prg/pipeline/speech/test_backends.py",
    "prg.pipeline.speech.backends.pocketsphinx": "tested with its package in tests/prg/pipeline/speech/test_backends.py",
    "prg.pipeline.speech.backends.wav2vec2": "tested with its package in tests/prg/pipeline/speech/test_backends.py",
    "prg.pipeline.speech.dependencies": "tested with its package in tests/prg/pipeline/test_speech.py",
    "prg.processes": "the job runner of paper_scale; run by tests/e2e/test_paper_scale.py",
    "prg.serving.writer_model": "the pyfunc model; served in tests/e2e/test_serving.py",
    "prg.sim.bullet": "the PyBullet scene, driven by tests/prg/sim/test_robots.py",
    "prg.sim.font": "the word placed on the paper, used by tests/prg/sim/ and tests/cli/test_simulate.py",
    "prg.tracking.lightning_logger": "tested with its package in tests/prg/test_tracking.py",
    "prg.tracking.naming": "tested with its package in tests/prg/test_tracking.py",
    "prg.tracking.pending": "tested with its package in tests/prg/test_tracking.py",
    "prg.tracking.relocation": "tested with its package in tests/prg/test_tracking.py",
    "prg.tracking.store": "tested with its package in tests/prg/test_tracking.py",
    "prg.training.generation_figures": "figures logged during training, in tests/prg/test_tracking.py",
    "prg.training.mlflow_logger": "the training logger, run by tests/prg/commands/test_train.py",
    "prg.training.settings": "training settings, composed by tests/prg/commands/test_train.py",
    "studies.analysis.analyze": "the analysis, run by tests/studies/analysis/test_participants.py",
    "studies.analysis.report.build": "the report, built by studies.analysis.commands in tests/studies/analysis/test_commands.py",
    "studies.analysis.report.document": "the report, built by studies.analysis.commands in tests/studies/analysis/test_commands.py",
    "studies.analysis.report.figures": "the report, built by studies.analysis.commands in tests/studies/analysis/test_commands.py",
    "studies.analysis.report.formatting": "the report, built by studies.analysis.commands in tests/studies/analysis/test_commands.py",
    "studies.analysis.report.sections": "the report, built by studies.analysis.commands in tests/studies/analysis/test_commands.py",
    "studies.analysis.report.write": "the report, built by studies.analysis.commands in tests/studies/analysis/test_commands.py",
    "studies.bundle": "the study bundle, built and served in tests/e2e/test_study_web.py",
    "studies.program": "the study program, built by tests/studies/test_cli.py",
    "studies.stimuli.json_samples": "sample files, read by tests/studies/stimuli/test_human.py",
    "studies.stimuli.sample": "the sample record, used by tests/studies/stimuli/",
    "studies.stimuli.write_settings": "stimulus writing settings, used by tests/studies/stimuli/test_robot.py",
}


def test_every_module_has_a_test_file_at_its_mirrored_path_or_says_why_not():
    missing = set()
    for root, base in ((SRC, SRC.parent), (REPO / "studies", REPO)):
        for path in root.rglob("*.py"):
            if path.name in ("__init__.py", "__main__.py"):
                continue
            rel = path.relative_to(base)
            if not (REPO / "tests" / rel.parent / f"test_{path.stem}.py").exists():
                missing.add(".".join(rel.with_suffix("").parts))
    unlisted = sorted(missing - UNMIRRORED.keys())
    assert not unlisted, f"modules without tests/<package path>/test_<module>.py: {unlisted}"
    tested = sorted(UNMIRRORED.keys() - missing)
    assert not tested, f"these now have a test file; take them off UNMIRRORED: {tested}"


#: One concept a module: no module of the library or of the study toolkit is longer than this.
MAX_MODULE_LINES = 600


def test_no_module_is_longer_than_one_concept_needs():
    long = {
        str(path.relative_to(REPO)): lines
        for root in (SRC, REPO / "studies")
        for path in root.rglob("*.py")
        if (lines := len(path.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES
    }
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them by concept): {long}"
