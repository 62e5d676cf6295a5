"""The README's figures, from the demo MUSE (models/muse/model.ckpt, made by `make demo`):

    python docs/make_figures.py

docs/figures/word.png: "jelly" from its labels (conf/write.yaml's settings, as `prg-write
text=jelly`): letters, connection strokes, delayed strokes, the DMP's rollout.
docs/figures/hands.png: "hello" in four hands (generate.hand_seed 0-3), each written twice (seeds
differ), beside the paper's posterior mean written twice. docs/figures/marks.png: the geometric check of the delayed strokes (dots of i/j, bars of t/f) on
the 62 classes and 200 random words (prg.evaluation.marks). docs/figures/robot.png: the Panda
writing "joy" (as `prg-simulate text=joy scale=6`), a TinyRenderer 3/4 view with a close-up of
the page. docs/figures/README.md: captions naming the checkpoint and its SHA-256. Atomic writes.
"""

from __future__ import annotations

import hashlib
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CKPT = ROOT / "models" / "muse" / "model.ckpt"
OUT = ROOT / "docs" / "figures"
WORD, ROBOT_WORD, SCALE = "jelly", "joy", 6.0  # SCALE: the robot's word, enlarged to be seen
EYE, TARGET = (-0.4, 1.0, 1.45), (0.42, 0.02, 0.85)  # world (m): the arm, table and page
CLOSE_EYE, CLOSE_TARGET = (0.31, 0.15, 0.82), (0.55, 0.03, 0.6255)  # the page, the whole word
LIGHT, SUPERSAMPLE, INK_MM = (-0.2, 0.5, 1.0), 2, 3.5  # ink drawn wide to show at this size


def save_atomic(path: Path, save) -> None:
    """``save(tmp)`` to a temporary file beside ``path`` (same suffix), then rename it."""
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        save(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def word_figure(writer, path: Path) -> str:
    """``WORD``: letters (black), connection strokes (red), delayed strokes (purple); beside it
    the body's DMP rollout by time and the delayed strokes after it."""
    from matplotlib.collections import LineCollection

    from prg.pipeline.timing import timed_body
    from prg.plotting import pyplot

    result = writer.write(text=WORD)
    word, rollout = result.word, result.rollout
    p = writer.settings
    target, _ = timed_body(word.body, p)
    rmse_mm = 10 * float(np.sqrt(np.mean(np.sum((rollout - target) ** 2, axis=1))))
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3), dpi=100, layout="constrained")
    colours = {"letter": "black", "connection": "tab:red", "mark": "tab:purple"}
    for kind, pts in word.polylines(highlight=False):
        left.plot(*pts.T, color=colours[kind], lw=2.5, solid_capstyle="round")
    left.set_title("letters, connection strokes (red), dots and bars (purple)", fontsize=10)
    t = np.linspace(0.0, word.dmp.tau, len(rollout))
    segments = np.stack([rollout[:-1], rollout[1:]], axis=1)
    lines = LineCollection(segments, array=t[:-1], cmap="viridis", lw=2.5, capstyle="round")
    right.add_collection(lines)
    for kind, pts in word.polylines(highlight=False):
        if kind == "mark":
            right.plot(*pts.T, color="tab:purple", lw=2.5, solid_capstyle="round")
    right.set_title("one DMP's rollout, then the dots and bars", fontsize=10)
    bar = fig.colorbar(lines, ax=right, shrink=0.7, aspect=15, pad=0.01)
    bar.set_label("time (s)")
    for ax in (left, right):
        ax.set_xlim(word.points[:, 0].min() - 0.3, word.points[:, 0].max() + 0.3)
        ax.set_ylim(word.points[:, 1].min() - 0.3, word.points[:, 1].max() + 0.3)
        ax.set_aspect("equal")
        ax.axis("off")
    save_atomic(path, lambda tmp: fig.savefig(tmp, dpi=100, metadata={"Software": None}))
    plt.close(fig)
    return (
        f'"{WORD}" written by the demo MUSE from its letters\' labels: {len(word.points)} points, '
        f"{word.path_length:.1f} cm of pen path (pen-up travel included) in "
        f"{word.duration_s:.1f} s; one DMP with {word.dmp.n_basis} basis functions reproduces the "
        f"cursive body ({word.dmp.tau:.1f} s) with RMSE {rmse_mm:.3f} mm, then the pen lifts to "
        f"dot and cross ({word.segment_kinds.count('mark')} delayed strokes)."
    )


HANDS_WORD, HANDS = "hello", 4


def hands_figure(writer, path: Path) -> str:
    """``HANDS_WORD`` in ``HANDS`` hands, each written twice (the same ``hand_seed``, two
    seeds), and the paper's posterior mean written twice (identical)."""
    from dataclasses import replace

    from prg.plotting import pyplot

    base = writer.settings
    rows = [
        (f"hand {h}", [replace(base, hand_seed=h, seed=100 + 2 * h + k) for k in (0, 1)])
        for h in range(HANDS)
    ]
    rows.append(("the paper (posterior mean)", [replace(base, mode="posterior")] * 2))
    plt = pyplot()
    fig, axes = plt.subplots(len(rows), 2, figsize=(7, 1.3 * len(rows)), dpi=100)
    for (name, settings), pair in zip(rows, axes, strict=True):
        for k, (ax, s) in enumerate(zip(pair, settings, strict=True)):
            writer.settings = s
            word = writer.write(text=HANDS_WORD).word
            for _, pts in word.polylines(highlight=False):
                ax.plot(*pts.T, color="black", lw=1.8, solid_capstyle="round")
            ax.set_aspect("equal")
            ax.axis("off")
            ax.set_title(f"{name}, writing {k + 1}", fontsize=9)
    writer.settings = base
    fig.tight_layout()
    save_atomic(path, lambda tmp: fig.savefig(tmp, dpi=100, metadata={"Software": None}))
    plt.close(fig)
    return (
        f'"{HANDS_WORD}" by the demo MUSE in {HANDS} hands (`generate.hand_seed=0..{HANDS - 1}`), '
        "each written twice with another `generate.seed` (the same person writing it again), "
        "and the paper's posterior-mean decoding (`generate.mode=posterior`) written twice: "
        "the same letters both times."
    )


def marks_figure(writer, path: Path) -> str:
    """The geometric check of the delayed strokes on the 62 classes and 200 random words."""
    from prg.evaluation.marks import check_writer
    from prg.evaluation.marks import marks_figure as draw

    check = check_writer(lambda text: writer.write(text=text).word, n_words=200, seed=0)
    draw(check, path)
    s = check.summary()
    failed = "; ".join(f"{w!r}: {' '.join(p)}" for w, p in list(s["failures"].items())[:5])
    return (
        f"Delayed strokes written by the demo MUSE from letter labels, checked on geometry "
        f"(`prg.evaluation.marks`): {s['classes_passed']}/{s['classes']} classes and "
        f"{s['words_passed']}/{s['words']} random words pass ({s['marks_checked']} dots and "
        f"bars: each dot above its stem within the letter's column, each bar crossing its "
        f"stem, no mark left over)" + (f"; failures: {failed}." if failed else ".")
    )


def robot_figure(writer, cfg, path: Path) -> str:
    """The Panda putting the last ink of ``ROBOT_WORD`` on the page (the j's dot, written after
    the word, so the whole word reads): a 3/4 view and, inset, a close-up of the page."""
    from PIL import Image

    from prg.commands.settings import simulation_settings
    from prg.sim import Scene, simulate_word
    from prg.sim.geometry import runs
    from prg.sim.ink import draw_strokes

    robot, settings = simulation_settings(cfg)
    word = writer.write(text=ROBOT_WORD).word
    result = simulate_word(word, robot, settings, render=False)
    step = np.flatnonzero(result.contact)[-1]  # the pen down on the last ink sample
    # every 6th ink sample: PIL's wide lines get ragged over many sub-pixel segments
    strokes = [
        np.vstack([result.tip_paper[a:b:6, :2], result.tip_paper[b - 1, :2]])
        for a, b in runs(result.contact)
    ]
    w, h = settings.paper.size_cm
    page = draw_strokes(strokes, (-w / 2, -h / 2), (round(w * 40), round(h * 40)), 40, INK_MM)
    k = SUPERSAMPLE
    with Scene(robot, settings.paper) as scene:
        q = scene.robot.rest_movable.copy()
        q[list(scene.robot.arm_in_movable)] = result.q[step]
        scene.reset(q)
        scene.show_ink(page)
        view = scene.render_view(EYE, TARGET, (900 * k, 600 * k), 40.0, light_direction=LIGHT)
        close = scene.render_view(
            CLOSE_EYE, CLOSE_TARGET, (330 * k, 220 * k), 40.0, light_direction=LIGHT
        )
    image = Image.fromarray(view).resize((900, 600), Image.LANCZOS)
    image.paste((90, 90, 90), (8, 8, 342, 232))  # the inset's frame
    image.paste(Image.fromarray(close).resize((330, 220), Image.LANCZOS), (10, 10))
    save_atomic(path, image.save)
    m = result.metrics
    return (
        f'The simulated Franka Panda (PyBullet, TinyRenderer) writing "{ROBOT_WORD}" from the demo '
        f"MUSE at {SCALE:g}x its size ({m['word_width_cm']:.1f} x {m['word_height_cm']:.1f} cm), "
        "as it puts the last ink on the page (the j's dot, written after the word); "
        f"inset: the page and the pen (ink drawn {INK_MM} mm wide). Tracking error mean "
        f"{m['tracking_error_mean_mm']:.3f} mm, max {m['tracking_error_max_mm']:.3f} mm."
    )


def main() -> None:
    if not CKPT.is_file():
        sys.exit(f"make_figures: {CKPT.relative_to(ROOT)} is missing: run `make demo` first")
    start = time.perf_counter()
    from prg.commands.cli import compose_config
    from prg.commands.settings import generate_settings
    from prg.writer import Writer

    digest = hashlib.sha256(CKPT.read_bytes()).hexdigest()[:12]
    cfg = compose_config("simulate", [f"scale={SCALE}"])
    writer = Writer.from_checkpoint(CKPT, settings=generate_settings(cfg))
    OUT.mkdir(parents=True, exist_ok=True)
    word_caption = word_figure(writer, OUT / "word.png")
    robot_caption = robot_figure(writer, cfg, OUT / "robot.png")
    marks_caption = marks_figure(writer, OUT / "marks.png")
    hands_caption = hands_figure(writer, OUT / "hands.png")
    text = (
        "# Figures\n\nGenerated by `python docs/make_figures.py` from "
        f"`{CKPT.relative_to(ROOT)}` (SHA-256 `{digest}...`); do not edit by hand.\n\n"
        f"![word](word.png)\n\n**word.png.** {word_caption}\n\n"
        f"![hands](hands.png)\n\n**hands.png.** {hands_caption}\n\n"
        f"![robot](robot.png)\n\n**robot.png.** {robot_caption}\n\n"
        f"![marks](marks.png)\n\n**marks.png.** {marks_caption}\n"
    )
    save_atomic(OUT / "README.md", lambda tmp: tmp.write_text(text, encoding="utf-8"))
    print(
        f"docs/figures: word.png, hands.png, robot.png, marks.png, README.md in {time.perf_counter() - start:.0f} s"
    )


if __name__ == "__main__":
    main()
