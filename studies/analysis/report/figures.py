"""The report's figures (matplotlib, drawn to PNG bytes): study 1's detection rates and
confidence, study 2's readability and paired differences."""

from __future__ import annotations

import numpy as np
import pandas as pd

from prg.plotting import pyplot

TRUTH_COLOR = "#c0392b"  #: the simulation's truth in the figures


def _png(fig) -> bytes:
    import io

    plt = pyplot()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def _label(ax, title: str, xlabel: str = "", ylabel: str = "", legend: bool = True, **where):
    """Title and axis labels of a figure's panel, and its small frameless legend (``where``:
    where it goes)."""
    if xlabel:
        ax.set_xlabel(xlabel)
    if ylabel:
        ax.set_ylabel(ylabel)
    if legend:
        ax.legend(frameon=False, fontsize=8, **where)
    ax.set_title(title)


def _participants_histogram(ax, values, bins) -> None:
    """A histogram of one value per participant, its y axis counting participants."""
    ax.hist(values, bins=bins, color="#8899cc", edgecolor="white")
    ax.set_ylabel("participants")


def fig_turing_words(
    per_word: pd.DataFrame,
    chance: float,
    margin: float,
    overall: tuple[float, float, float] | None,
    truth: float | None = None,
):
    """Per-word rates of picking the robot, Wilson CIs, chance and the equivalence band; with
    simulated data the true rate (``truth``) and each word's (``per_word["truth"]``)."""
    plt = pyplot()
    pw = per_word.sort_values("rate")
    fig, ax = plt.subplots(figsize=(6.4, 0.35 * len(pw) + 1.6))
    y = np.arange(len(pw))
    ax.axvspan(
        chance - margin,
        chance + margin,
        color="#cfe8cf",
        label=f"equivalence band {chance:g} ± {margin:g}",
    )
    ax.axvline(chance, color="#2a7f2a", lw=1.2, label=f"chance {chance:g}")
    if overall is not None:
        est, lo, hi = overall
        ax.axvspan(lo, hi, color="#d9d9f3", alpha=0.8)
        ax.axvline(est, color="#33338f", lw=1.2, ls="--", label=f"overall (GEE) {est:.2f}")
    ax.errorbar(
        pw["rate"],
        y,
        xerr=[pw["rate"] - pw["ci_low"], pw["ci_high"] - pw["rate"]],
        fmt="o",
        color="black",
        capsize=3,
    )
    if truth is not None:
        ax.axvline(truth, color=TRUTH_COLOR, ls=":", lw=1.6, label=f"simulated truth {truth:.2f}")
    if "truth" in pw:
        ax.plot(pw["truth"], y, "x", color=TRUTH_COLOR, ms=7, label="true rate of the word")
    ax.set_yticks(y, pw["word"].astype(str))
    ax.set_xlim(0, 1)
    _label(
        ax,
        "Study 1: per-word detection rate against chance",
        "rate of picking the robot's sample (95 % Wilson CI)",
        loc="lower right",
    )
    return fig


def fig_turing_participants(per_part: pd.DataFrame, chance: float):
    """Histogram of the participants' rates of picking the robot."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 3.0))
    bins = np.arange(-0.025, 1.026, 0.05)  # centred on multiples of 0.05 (rates of 10 or 20 trials)
    _participants_histogram(ax, per_part["rate"], bins)
    ax.axvline(chance, color="#2a7f2a", lw=1.2, label=f"chance {chance:g}")
    _label(
        ax,
        "Study 1: participants' detection rates",
        "participant's rate of picking the robot's sample",
    )
    return fig


def fig_confidence(data: pd.DataFrame, neutral: float, truth: float | None = None):
    """Confidence ratings (by whether the robot was picked) and participant mean confidence
    (and, simulated, the true mean ``truth``)."""
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.2))
    levels = np.arange(1, 6)
    width = 0.4
    for shift, (val, label, color) in zip(
        (-width / 2, width / 2),
        ((1.0, "picked the robot", "#33338f"), (0.0, "picked a human", "#b0b0b0")),
    ):
        counts = (
            data.loc[data["chose_robot"] == val, "confidence"]
            .value_counts()
            .reindex(levels, fill_value=0)
        )
        a1.bar(levels + shift, counts.to_numpy(), width=width, label=label, color=color)
    a1.set_xticks(levels, ["very\nlow", "low", "neutral", "high", "very\nhigh"])
    _label(a1, "Confidence ratings", ylabel="ratings")
    means = data.groupby("participant_id")["confidence"].mean()
    _participants_histogram(a2, means, np.linspace(1, 5, 17))
    a2.axvline(neutral, color="black", lw=1.2, label=f"neutral {neutral:g}")
    a2.axvline(
        means.mean(), color="#33338f", ls="--", lw=1.2, label=f"mean of means {means.mean():.2f}"
    )
    if truth is not None:
        a2.axvline(truth, color=TRUTH_COLOR, ls=":", lw=1.6, label=f"simulated truth {truth:.2f}")
    _label(a2, "One value per participant", "participant's mean confidence")
    fig.tight_layout()
    return fig


def fig_readability(per_word: pd.DataFrame, data: pd.DataFrame, truth: dict | None = None):
    """Success rate per writer (Wilson CI) and per word, human vs robot; simulated, the true
    rate of each writer (``truth``: writer -> rate)."""
    from studies.analysis.stats import proportion_ci

    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6), gridspec_kw={"width_ratios": [1, 2.2]})
    colors = {"human": "#b07030", "robot": "#33338f"}
    for i, w in enumerate(("human", "robot")):
        y = data.loc[data["writer"] == w, "correct"]
        if len(y) == 0:
            continue
        k, n = int(y.sum()), len(y)
        lo, hi = proportion_ci(k, n)
        a1.errorbar(
            [i],
            [k / n],
            yerr=[[k / n - lo], [hi - k / n]],
            fmt="o",
            color=colors[w],
            capsize=4,
            ms=8,
        )
        prates = data[data["writer"] == w].groupby("participant_id")["correct"].mean()
        jitter = np.random.default_rng(i).uniform(-0.12, 0.12, len(prates))
        a1.scatter(i + 0.3 + jitter, prates, s=8, color=colors[w], alpha=0.35)
        if truth is not None:
            label = "simulated truth" if i == 0 else None
            a1.plot([i], [truth[w]], "x", color=TRUTH_COLOR, ms=10, mew=2, label=label)
    a1.set_xticks([0, 1], ["human", "robot"])
    a1.set_xlim(-0.5, 1.7)
    a1.set_ylim(-0.02, 1.02)
    _label(
        a1,
        "Readability per writer",
        ylabel="success rate (95 % Wilson CI; dots: participants)",
        legend=truth is not None,
        loc="lower left",
    )
    wide = per_word.pivot_table(index="word", columns="writer", values="rate")
    wide = wide.sort_values(wide.columns[0]) if len(wide.columns) else wide
    x = np.arange(len(wide))
    for w in ("human", "robot"):
        if w in wide:
            a2.plot(x, wide[w], "o", color=colors[w], label=w)
    if {"human", "robot"} <= set(wide.columns):
        a2.vlines(x, wide["human"], wide["robot"], color="#999999", lw=1)
    a2.set_xticks(x, wide.index.astype(str), rotation=45, ha="right")
    a2.set_ylim(-0.02, 1.02)
    _label(a2, "Per word: the same word in both writings", ylabel="success rate")
    fig.tight_layout()
    return fig


def fig_differences(
    per_part: pd.DataFrame,
    margin: float,
    diff: tuple[float, float, float] | None,
    truth: float | None = None,
):
    """Participants' robot-minus-human differences with the equivalence band (and, simulated,
    the true difference ``truth``)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 3.0))
    d = per_part["difference"].dropna() if "difference" in per_part else pd.Series(dtype=float)
    ax.axvspan(-margin, margin, color="#cfe8cf", label=f"equivalence band ±{margin:g}")
    _participants_histogram(ax, d, np.arange(-1.05, 1.06, 0.1))
    ax.axvline(0, color="black", lw=0.8)
    if diff is not None:
        est, lo, hi = diff
        ax.axvspan(
            lo, hi, color="#33338f", alpha=0.25, zorder=3, label="90 % CI of the mean (TOST)"
        )
        ax.axvline(est, color="#33338f", lw=1.8, zorder=4, label=f"mean difference {est:+.3f}")
    if truth is not None:
        ax.axvline(
            truth,
            color=TRUTH_COLOR,
            ls=":",
            lw=1.8,
            zorder=5,
            label=f"simulated truth {truth:+.3f}",
        )
    _label(ax, "Study 2: paired differences", "participant's success rate: robot minus human")
    return fig
