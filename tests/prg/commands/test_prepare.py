"""Same seed, same data: two runs of the `prg-prepare` task write byte-identical files — the
splits, the manifest, the figures and the DVC metrics, compared file by file (sha256)."""

import hashlib
from pathlib import Path

from prg.commands.cli import compose_config
from prg.commands.prepare import prepare

SMALL = [
    "data.synthetic.n_writers=4",
    "data.augment.per_class=1",
    "data.splits.train=0.5",
    "data.splits.val=0.25",
    "data.splits.test=0.25",
    "workers=1",
    "progress=false",
]


def _digests(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def test_two_prepare_runs_write_identical_files(tmp_path):
    runs = []
    for name in ("a", "b"):
        prepare(compose_config("prepare", [f"paths.root_dir={tmp_path / name}", *SMALL]))
        runs.append(_digests(tmp_path / name))
    first, second = runs
    names = sorted(first)
    assert [n for n in names if n.endswith(".npz")] == [
        f"data/prepared/synthetic/{s}.npz" for s in ("test", "train", "val")
    ]
    assert "data/prepared/synthetic/manifest.json" in names
    assert "reports/prepare/synthetic/metrics.json" in names
    assert len([n for n in names if n.endswith(".png")]) == 3
    assert first == second
