"""How close other writers' real letters come to the test writers, by the synthetic writer's font.

    python docs/notes/likeness_by_font.py                      # real letters only (about 1 min)
    python docs/notes/likeness_by_font.py --ckpt converged/models/muse/model.ckpt \\
        --classifier converged/models/classifiers/traj.pt     # and the model's hands by font

The measure of the likeness report (``prg.evaluation.modes.score``: k-NN precision and recall,
C2ST, against the test split's letters, 10 letters per class), on letters drawn from one font's
writers of a split at a time (``--draws`` draws, averaged), and, with ``--ckpt``, on letters the
model writes in the default hand mode with its hands drawn among one font's training writers
only. Each synthetic writer writes one font (``prg.data.synthetic.writer_styles``), so the rows
say how much of the precision the test split's mix of fonts allows (docs/results.md, the
converged profile). Prints a Markdown table, row by row; ``--out FILE`` also writes it as JSON.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

from prg.alphabet import NUM_CLASSES  # noqa: E402
from prg.errors import UsageError, UsageParser  # noqa: E402
from prg.files import json_text, write_text  # noqa: E402

N_PER_CLASS = 10
K = 3  # the likeness report's k-NN neighbours (prg.evaluation.likeness)


def writer_fonts(data_dir: Path) -> dict[str, str]:
    """Each synthetic writer's font, from the generator's own assignment and the dataset's
    recorded settings."""
    from prg.data.synthetic import SyntheticSettings, writer_styles

    manifest = json.loads((data_dir / "manifest.json").read_text())
    if manifest.get("source") != "synthetic":
        raise UsageError(f"{data_dir}: a {manifest.get('source')} dataset has no fonts")
    settings = manifest["config"]["synthetic"]
    styles = writer_styles(
        SyntheticSettings(n_writers=settings["n_writers"], fonts=tuple(settings["fonts"]))
    )
    return {f"SYN_W{w + 1:02d}": style.font for w, style in enumerate(styles)}


def main(argv: list[str] | None = None) -> int:
    parser = UsageParser(prog="likeness_by_font.py", description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=ROOT / "data/prepared/synthetic")
    parser.add_argument("--ckpt", type=Path, help="a checkpoint with hands (default: none)")
    parser.add_argument("--classifier", type=Path, default=ROOT / "models/classifiers/traj.pt")
    parser.add_argument("--draws", type=int, default=3)
    parser.add_argument("--out", type=Path, help="also write the rows as JSON")
    try:
        args = parser.parse_args(argv)
        if args.draws < 1:
            raise UsageError(f"--draws must be at least 1, got {args.draws}")
        for path in (args.data / "test.npz", args.classifier, args.ckpt):
            if path is not None and not path.is_file():
                raise UsageError(f"{path}: no such file")
        rows = measure(args)
    except UsageError as err:
        print(f"likeness_by_font.py: error: {err}", file=sys.stderr)
        return 2
    if args.out:
        write_text(args.out, json_text(rows))
    return 0


def measure(args) -> list[dict]:
    import torch

    from prg.data.store import load_split
    from prg.evaluation.classifiers import load_classifier, predict
    from prg.evaluation.modes import by_class, originals, score, subsample

    torch.set_num_threads(2)
    fonts = writer_fonts(args.data)
    classifier, _ = load_classifier(args.classifier)
    hands = load_hands(args.ckpt) if args.ckpt else None

    def classify(letters: np.ndarray) -> np.ndarray:
        return predict(classifier, torch.from_numpy(letters)).numpy()

    splits = {s: originals(load_split(args.data / f"{s}.npz")) for s in ("test", "val", "train")}
    real = by_class(*splits["test"][:2])
    fewest = min(len(letters) for letters in real.values())
    if fewest <= K:
        raise UsageError(
            f"{args.data / 'test.npz'}: a class has {fewest} test letters; the k-NN measures"
            f" need more than k = {K} (a dataset with more test writers)"
        )
    names = list(dict.fromkeys(fonts.values()))  # the fonts in the generator's order
    rows: list[dict] = []
    print("| letters | writers | font | n writers | legible | precision | recall | c2st |")
    print("|---|---|---|---|---|---|---|---|")

    def report(kind: str, split: str, font: str, n_writers: int, scores: list[dict]) -> None:
        mean = {k: float(np.mean([s[k] for s in scores])) for k in scores[0]}
        rows.append(
            {"letters": kind, "writers": split, "font": font, "n_writers": n_writers, **mean}
        )
        print(
            f"| {kind} | {split} | {font} | {n_writers} | {mean['legible']:.2f} | "
            f"{mean['precision']:.2f} | {mean['recall']:.2f} | {mean['c2st']:.2f} |",
            flush=True,
        )

    for split, (traj, labels, writers) in splits.items():
        font_of = np.array([fonts[w] for w in writers])
        for font in [*names, "all"]:
            keep = font_of == font if font != "all" else np.ones(len(writers), bool)
            n_writers = len(set(writers[keep]))
            if split == "test":  # the reference: counted, not scored
                rows.append(
                    {"letters": "real", "writers": split, "font": font, "n_writers": n_writers}
                )
                print(f"| real (the reference) | test | {font} | {n_writers} | | | | |")
                continue
            if n_writers == 0:
                continue
            try:
                scores = [
                    score(subsample(traj[keep], labels[keep], N_PER_CLASS, s), real, classify, s)
                    for s in range(args.draws)
                ]
            except ValueError:  # a class none of these writers wrote
                continue
            report("real", split, font, n_writers, scores)
    if hands:
        report_hands(*hands, fonts, names, real, classify, report)
    return rows


def load_hands(ckpt: Path):
    """The model of ``ckpt`` and the hands its checkpoint keeps."""
    from prg.models.checkpoint import load_model

    model, extra = load_model(ckpt)
    if extra.get("hands") is None:
        raise UsageError(f"{ckpt}: the checkpoint keeps no hands")
    return model, extra["hands"]


def report_hands(model, bank, fonts, names, real, classify, report) -> None:
    """The model's default hand mode, its hands drawn among one font's writers."""
    from prg.evaluation.modes import score
    from prg.pipeline.hands import Hand, components, decode_in_hand, decoder_bias
    from prg.pipeline.settings import GenerateSettings

    temperature = GenerateSettings().hand_temperature
    bias = decoder_bias(model, bank)
    bank_font = np.array([fonts[w] for w in bank.writers])
    labels = np.arange(NUM_CLASSES)
    for font in [*names, "all"]:
        writers = np.flatnonzero(bank_font == font) if font != "all" else np.arange(len(bank_font))
        if len(writers) == 0:
            continue
        letters = []
        for i in range(N_PER_CLASS):
            rng = np.random.default_rng(1000 + i)
            seeds = i * NUM_CLASSES + labels
            chosen = np.concatenate(
                [
                    components(bank, Hand(int(rng.choice(writers))), labels[c : c + 1], int(s))
                    for c, s in enumerate(seeds)
                ]
            )
            letters.append(
                decode_in_hand(model, chosen, labels, temperature, i, bias).reshape(NUM_CLASSES, -1)
            )
        generated = np.stack(letters)
        scores = [score({c: generated[:, c] for c in range(NUM_CLASSES)}, real, classify, 0)]
        report(f"{model.family} hand", "train", font, len(writers), scores)


if __name__ == "__main__":
    sys.exit(main())
