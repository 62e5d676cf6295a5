"""The analysis report: Markdown and self-contained HTML, figures, tidy CSVs — written atomically.

:func:`write_report` turns an :class:`~studies.analysis.analyze.Analysis` into a folder::

    report.md            the report (figures linked from figures/)
    report.html          the same report, figures embedded as base64 PNG (one file to send)
    tests.csv            one row per test: study, approach, hypothesis, estimate, CI, statistic, p, conclusion
    per_word.csv         per-word rates with Wilson CIs (study 1: p vs chance, Holm-adjusted)
    per_participant.csv  per-participant rates with CIs (+ confidence / per-writer rates), attention checks
    mixed_model.csv      crossed mixed-logit terms (or why the fit failed)
    paper_reproduction.csv  the paper's numbers reproduced from its summaries
    metrics.json         the verdicts, machine-readable
    figures/*.png

Everything is written into a temporary folder next to ``out`` and renamed into place, so a
failed run leaves the previous report untouched.
"""

from __future__ import annotations

import base64
import html
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from prg.errors import UsageError
from prg.files import staged_folder
from prg.plotting import pyplot
from studies.analysis.analyze import Analysis, StudyAnalysis
from studies.analysis.schema import TURING

REPORT_FILES = ("report.md", "report.html", "tests.csv")
TRUTH_COLOR = "#c0392b"  #: the simulation's truth in the figures


# --------------------------------------------------------------------------- a tiny document model


@dataclass
class Doc:
    """Blocks rendered to both Markdown and HTML (text may use **bold**, *italic*, `code`)."""

    title: str
    blocks: list[tuple] = field(default_factory=list)

    def h(self, level: int, text: str) -> None:
        self.blocks.append(("h", level, text))

    def p(self, text: str) -> None:
        self.blocks.append(("p", text))

    def ul(self, items: list[str]) -> None:
        if items:
            self.blocks.append(("ul", list(items)))

    def warn(self, text: str) -> None:
        self.blocks.append(("warn", text))

    def banner(self, head: str, text: str) -> None:
        """A notice that cannot be missed, e.g. that the data are simulated."""
        self.blocks.append(("banner", head, text))

    def table(self, frame: pd.DataFrame, caption: str = "") -> None:
        self.blocks.append(("table", frame.astype(str), caption))

    def figure(self, name: str, png: bytes, caption: str) -> None:
        self.blocks.append(("fig", name, png, caption))

    def markdown(self) -> str:
        out = [f"# {self.title}", ""]
        for b in self.blocks:
            kind = b[0]
            if kind == "h":
                out += ["#" * b[1] + " " + b[2], ""]
            elif kind == "p":
                out += [b[1], ""]
            elif kind == "ul":
                out += [f"- {item}" for item in b[1]] + [""]
            elif kind == "warn":
                out += [f"> **Warning:** {b[1]}", ""]
            elif kind == "banner":
                out += [f"> **{b[1]}** — {b[2]}", ""]
            elif kind == "table":
                frame, caption = b[1], b[2]
                if caption:
                    out += [f"*{caption}*", ""]
                cells = [[_md_cell(c) for c in frame.columns]] + [
                    [_md_cell(v) for v in row] for row in frame.itertuples(index=False)
                ]
                out.append("| " + " | ".join(cells[0]) + " |")
                out.append("|" + "|".join("---" for _ in cells[0]) + "|")
                out += ["| " + " | ".join(r) + " |" for r in cells[1:]]
                out.append("")
            elif kind == "fig":
                out += [f"![{b[3]}](figures/{b[1]})", "", f"*{b[3]}*", ""]
        return "\n".join(out).rstrip() + "\n"

    def html(self) -> str:
        body = [f"<h1>{_inline(self.title)}</h1>"]
        for b in self.blocks:
            kind = b[0]
            if kind == "h":
                body.append(f"<h{b[1]}>{_inline(b[2])}</h{b[1]}>")
            elif kind == "p":
                body.append(f"<p>{_inline(b[1])}</p>")
            elif kind == "ul":
                body.append("<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in b[1]) + "</ul>")
            elif kind == "warn":
                body.append(f'<p class="warn"><strong>Warning:</strong> {_inline(b[1])}</p>')
            elif kind == "banner":
                body.append(
                    f'<div class="banner" role="note"><strong>{_inline(b[1])}</strong> — '
                    f"{_inline(b[2])}</div>"
                )
            elif kind == "table":
                frame, caption = b[1], b[2]
                cap = f"<caption>{_inline(caption)}</caption>" if caption else ""
                head = "".join(f"<th>{_inline(c)}</th>" for c in frame.columns)
                rows = "".join(
                    "<tr>" + "".join(f"<td>{_inline(v)}</td>" for v in row) + "</tr>"
                    for row in frame.itertuples(index=False)
                )
                body.append(
                    f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>"
                )
            elif kind == "fig":
                data = base64.b64encode(b[2]).decode("ascii")
                body.append(
                    f'<figure><img alt="{html.escape(b[3])}" src="data:image/png;base64,{data}">'
                    f"<figcaption>{_inline(b[3])}</figcaption></figure>"
                )
        return (
            '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head>\n<body>\n"
            + "\n".join(body)
            + "\n</body></html>\n"
        )


_CSS = (
    "body{font-family:system-ui,sans-serif;max-width:60em;margin:2em auto;padding:0 1em;line-height:1.45;color:#222}"
    "table{border-collapse:collapse;margin:0.5em 0 1.5em;font-size:0.88em}"
    "th,td{border:1px solid #ccc;padding:0.25em 0.5em;text-align:left;vertical-align:top}"
    "th{background:#f3f3f3}caption{caption-side:top;text-align:left;font-style:italic;padding:0.3em 0}"
    "figure{margin:1em 0}img{max-width:100%}figcaption{font-style:italic;font-size:0.9em}"
    ".warn{background:#fff4e0;border-left:4px solid #e69500;padding:0.5em}"
    ".banner{background:#a3142d;color:#fff;padding:0.6em 0.9em;border-radius:4px;margin:0 0 1em}"
    ".banner strong{font-size:1.15em;margin-right:0.3em}.banner code{background:#0003}"
    "code{background:#f3f3f3;padding:0 0.2em}"
)


def _md_cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _inline(text: str) -> str:
    s = html.escape(str(text))
    s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
    s = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", s)
    s = re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<em>\1</em>", s)
    return s


# --------------------------------------------------------------------------- formatting


def fmt_p(p: float) -> str:
    """A p value for people: 3 decimals, or 2 significant digits below 0.001."""
    if p is None or not np.isfinite(p):
        return "–"
    return f"{p:.2g}" if p < 0.001 else f"{p:.3f}"


def _num(x: float, digits: int = 3) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{x:.{digits}f}"


def tests_table(tests: pd.DataFrame, digits: int = 3) -> pd.DataFrame:
    """The human-readable view of a tests frame (with its ``truth`` beside the estimate when it
    has one: see :mod:`studies.analysis.truth`)."""
    rows = []
    for r in tests.itertuples(index=False):
        if np.isfinite(r.estimate):
            hi = "∞" if r.ci_high == np.inf else _num(r.ci_high, digits)
            est = (
                f"{_num(r.estimate, digits)} [{_num(r.ci_low, digits)}, {hi}]"
                if np.isfinite(r.ci_low)
                else _num(r.estimate, digits)
            )
            lvl = f"{r.ci_level:.0%}" if np.isfinite(r.ci_level) else ""
        else:
            est, lvl = "–", ""
        row = {
            "approach": r.approach,
            "test": r.test,
            "n": ""
            if not np.isfinite(r.n)
            else f"{r.n:.0f}"
            + (f" ({r.clusters:.0f} clusters)" if np.isfinite(r.clusters) else ""),
            "estimate [CI]": est,
        }
        if "truth" in tests:  # simulated data: what the estimate should recover
            row["truth"] = _num(r.truth, digits)
        row |= {"CI": lvl, "p": fmt_p(r.p_value), "conclusion": r.conclusion}
        rows.append(row)
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- figures


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


# --------------------------------------------------------------------------- the report


def _row(tests: pd.DataFrame, name: str):
    hit = tests[tests["test"] == name]
    return hit.iloc[0] if len(hit) else None


def _truth_column(frame: pd.DataFrame) -> list[str]:
    """``["truth"]`` when ``frame`` has the simulation's truth beside its estimates, else ``[]``."""
    return ["truth"] if "truth" in frame else []


def _interval(tests: pd.DataFrame, name: str) -> tuple[float, float, float] | None:
    """(estimate, ci_low, ci_high) of the test ``name``; None when it is missing or not estimated."""
    row = _row(tests, name)
    if row is None or not np.isfinite(row.estimate):
        return None
    return row.estimate, row.ci_low, row.ci_high


def _study1_section(doc: Doc, st: StudyAnalysis) -> None:
    cfg, c, m, truth = st.config, st.config.chance, st.margin, st.truth
    d = st.data
    doc.h(2, "Study 1: Turing-like test")
    doc.p(
        f"{d['participant_id'].nunique()} participants, {d['word'].nunique()} words, {len(d)} trials. On each trial a "
        f"participant saw {cfg.n_options} samples of a word (one by the robot) and picked the one they thought the robot "
        f"wrote, then rated their confidence 1-5. Guessing picks the robot with probability {c:g}. "
        f"**H1** (indistinguishable): the rate is within {c:g} ± {m:g}. **H2** (low confidence): mean confidence is not "
        f"above neutral ({cfg.neutral:g})."
    )
    for w in st.warnings:
        doc.warn(w)
    doc.h(3, "H1: can participants tell the robot's writing apart?")
    h1 = st.tests[st.tests["hypothesis"].str.startswith("H1")]
    doc.table(
        tests_table(h1),
        "Tests of H1. Paper-faithful rows treat all trials as independent; recommended rows allow for participants.",
    )
    overall = _interval(st.tests, "GEE rate vs chance")
    doc.figure(
        "turing_per_word.png",
        _png(fig_turing_words(st.per_word, c, m, overall, truth and truth.rate)),
        "Rate of picking the robot's sample per word (95 % Wilson CIs, trials independent within a word); "
        "green: chance and the equivalence band; blue: the overall GEE estimate and its 95 % CI.",
    )
    columns = ["word", "n", "k", "rate", "ci_low", "ci_high", "p_vs_chance", "p_holm"]
    pw = st.per_word[[*columns, *_truth_column(st.per_word), "mean_confidence"]].copy()
    for col in ("rate", "ci_low", "ci_high", *_truth_column(st.per_word)):
        pw[col] = pw[col].map(_num)
    pw["p_vs_chance"] = pw["p_vs_chance"].map(fmt_p)
    pw["p_holm"] = pw["p_holm"].map(fmt_p)
    pw["mean_confidence"] = pw["mean_confidence"].map(lambda x: _num(x, 2))
    doc.table(
        pw,
        "Per word: robot picks k of n, rate with 95 % Wilson CI, exact two-sided binomial test vs chance (Holm-adjusted over words).",
    )
    icc = st.icc.set_index("value")
    if "chose_robot" in icc.index and not np.isfinite(icc.loc["chose_robot"].icc):
        doc.p(
            "The ICC of the 0/1 answers is not estimable from these data (every answer the same, "
            "or fewer than 2 participants), so neither is the design effect."
        )
    elif "chose_robot" in icc.index:
        r = icc.loc["chose_robot"]
        doc.p(
            f"Answers cluster within participants: the ICC of the 0/1 answers is {_num(r.icc)} "
            f"(design effect {_num(r.design_effect, 2)} for {r.mean_cluster_size:.3g} trials per participant), "
            f"so {len(d)} trials carry the information of about {len(d) / max(r.design_effect, 1):.0f} independent ones."
        )
    doc.figure(
        "turing_participants.png",
        _png(fig_turing_participants(st.per_participant, c)),
        "Participants' own rates of picking the robot's sample.",
    )
    doc.h(3, "Crossed mixed logit (sensitivity analysis)")
    _mixed(doc, st.mixed, "rate of a typical participant on a typical word")
    doc.h(3, "H2: how confident were participants?")
    h2 = st.tests[st.tests["hypothesis"].str.startswith("H2")]
    doc.table(tests_table(h2, 2), "Tests of H2 against the neutral rating.")
    if "confidence" in icc.index:
        r = icc.loc["confidence"]
        doc.p(
            f"Ratings cluster within participants (ICC {_num(r.icc)}, design effect {_num(r.design_effect, 2)}): the "
            "paper-faithful test's n counts every rating as a separate person; the recommended test uses one mean per "
            "participant. Ratings are ordinal, so a signed-rank test on the participant means is shown as a check."
        )
    doc.figure(
        "turing_confidence.png",
        _png(fig_confidence(d, cfg.neutral, truth and truth.confidence_mean)),
        "Left: confidence ratings split by whether the robot's sample was picked. Right: participants' mean confidence.",
    )


def _mixed(doc: Doc, mixed: pd.DataFrame, what: str) -> None:
    if mixed is None or mixed.empty:
        doc.p("The crossed mixed logit was not fitted (`--no-mixed`).")
        return
    status = str(mixed["status"].iloc[0])
    if status.startswith("skipped"):
        doc.p(f"The crossed mixed logit was skipped: {status[len('skipped: ') :]}.")
        return
    if status.startswith("failed"):
        doc.warn(
            f"The crossed mixed logit (participants x words) could not be fitted: {status[len('failed: ') :]}. "
            "The GEE results above do not depend on it."
        )
        return
    t = mixed.copy()
    view = pd.DataFrame(
        {
            "term": t["term"],
            "type": t["type"],
            "posterior mean": t["post_mean"].map(_num),
            **({"truth": t["truth"].map(_num)} if "truth" in t else {}),
            "95 % interval": [f"[{_num(a)}, {_num(b)}]" for a, b in zip(t["ci_low"], t["ci_high"])],
            "as a rate": [
                f"{_num(r)} [{_num(a)}, {_num(b)}]" if np.isfinite(r) else ""
                for r, a, b in zip(t["rate"], t["rate_low"], t["rate_high"])
            ],
        }
    )
    doc.table(
        view,
        "Crossed random intercepts for participants and words (BinomialBayesMixedGLM, variational Bayes).",
    )
    doc.p(
        f"*Caveat*: this model is fitted by mean-field variational Bayes (statsmodels' `BinomialBayesMixedGLM.fit_vb`, "
        f"priors N(0, 2²) on fixed effects and N(0, 1) on log random-effect SDs). Its intervals are approximate and "
        f"typically too narrow, and its intercept is the {what}, not the population-average rate the GEE estimates. "
        f"It is shown because it is the one analysis here that allows for word-to-word variation as well as "
        f"participants; status: {status}."
    )


def _study2_section(doc: Doc, st: StudyAnalysis) -> None:
    m, truth = st.margin, st.truth
    d = st.data
    doc.h(2, "Study 2: readability")
    lists = d["list_id"].replace("", np.nan).dropna().unique() if "list_id" in d else []
    doc.p(
        f"{d['participant_id'].nunique()} participants typed the word they saw; {len(d)} trials over "
        f"{d['word'].nunique()} words, each participant reading words by both writers"
        + (
            f" (lists {', '.join(map(str, sorted(lists)))} swap who wrote which word)"
            if len(lists)
            else ""
        )
        + f". The question is whether the robot's words are as readable as the human's: equivalence within ±{m:g} "
        f"(TOST), or at least non-inferiority (robot ≥ human − {m:g})."
    )
    for w in st.warnings:
        doc.warn(w)
    doc.table(
        tests_table(st.tests),
        "Tests of readability (robot minus human). The paper-faithful test ignores the pairing.",
    )
    doc.figure(
        "readability_per_writer.png",
        _png(
            fig_readability(
                st.per_word,
                d,
                truth and {"human": truth.human_rate, "robot": truth.robot_rate},
            )
        ),
        "Left: success rate per writer (95 % Wilson CI), dots are participants. Right: each word's success rate in both writings.",
    )
    diff = _interval(st.tests, f"paired TOST by participant (±{m:g})")
    doc.figure(
        "readability_differences.png",
        _png(
            fig_differences(
                st.per_participant, m, diff, truth and truth.robot_rate - truth.human_rate
            )
        ),
        f"Participants' robot-minus-human differences; equivalence needs the 90 % CI inside ±{m:g}.",
    )
    pw = st.per_word.copy()
    for col in ("rate", "ci_low", "ci_high", *_truth_column(pw)):
        pw[col] = pw[col].map(_num)
    doc.table(
        pw[["word", "writer", "n", "k", "rate", "ci_low", "ci_high", *_truth_column(pw)]],
        "Per word and writer: k of n typed correctly, rate with 95 % Wilson CI.",
    )
    doc.h(3, "Crossed mixed logit (sensitivity analysis)")
    _mixed(
        doc,
        st.mixed,
        "log-odds of a typical participant on a typical word (the writer term is the robot-vs-human log-odds ratio)",
    )


def _paper_section(doc: Doc, reproduced: pd.DataFrame | None, analysis: Analysis) -> None:
    from studies.analysis.paper import WEAKNESSES

    doc.h(2, "Where the paper's analysis was weak")
    doc.p(
        'The paper ("User Study on PRG against Human Calligraphy") reports summary numbers only. Re-running its tests '
        "from those numbers reproduces its conclusions, and shows where the analysis falls short:"
    )
    doc.ul([f"**{head}** {body}" for head, body in WEAKNESSES])
    contrasts = [c for st in analysis.studies for c in st.contrasts]
    if contrasts:
        doc.p(
            "On the data analysed in this report, the paper's way of testing and the recommended one disagree:"
        )
        doc.ul(contrasts)
    if reproduced is not None:
        view = reproduced[["study", "quantity", "shown", "expected", "note"]].rename(
            columns={"shown": "reproduced", "expected": "re-analysis (studies.md)"}
        )
        doc.table(
            view,
            "The paper's numbers reproduced from its summaries (data rebuilt to match them; see studies.analysis.paper).",
        )


def _methods(doc: Doc, analysis: Analysis) -> None:
    import scipy
    import statsmodels

    cfg = analysis.config
    doc.h(2, "Methods")
    doc.ul(
        [
            "**Paper-faithful**: exact binomial test of the robot-pick rate against chance (one-sided), exact binomial "
            "TOST on chance ± margin, one-sided t-test of all confidence ratings against neutral, and (study 2) an "
            "independent two-sample t-test on the words' success rates. All treat trials as independent.",
            "**GEE**: logit link with offset logit(chance), exchangeable working correlation within participants, "
            "bias-reduced (Mancl-DeRouen) sandwich standard errors; TOST on the logit scale against "
            "logit(chance ± margin). Study 2: identity link for the robot-minus-human difference.",
            "**Participant-level tests**: one value per participant (mean confidence; rate; robot-minus-human "
            "difference) in one-sample or paired t-tests (`scipy.stats`), the paired TOST with "
            "`statsmodels.stats.weightstats.ttost_paired`, non-inferiority as a one-sided paired t-test against −margin. "
            "By-word paired tests treat words as the unit instead.",
            "**Crossed mixed logit**: random intercepts for participants and words, `BinomialBayesMixedGLM.fit_vb`.",
            "**Equivalence**: shown when both one-sided nulls are rejected at alpha, i.e. when the 1 − 2·alpha CI lies "
            "inside the margin. Not rejecting 'no difference' is never read as equality.",
            f"**Options**: chance {cfg.chance:g}, alpha {cfg.alpha:g}, margin source {cfg.margin_source}"
            + (f", config {cfg.source}" if cfg.source else "")
            + f"; attention-check rows {'included' if cfg.include_attention_rows else 'excluded'}; participants failing "
            f"an attention check {'excluded' if cfg.exclude_failed_attention else 'kept'}.",
            f"Software: scipy {scipy.__version__}, statsmodels {statsmodels.__version__}.",
        ]
    )
    doc.p(
        "Files: `tests.csv` (one row per test), `per_word.csv`, `per_participant.csv`, `mixed_model.csv`, "
        "`paper_reproduction.csv`, `metrics.json` (the verdicts), `figures/`."
    )


ORIGIN_TITLES = {"simulated": " — SIMULATED participants", "pilot": " — PILOT data"}


def _origin_banner(doc: Doc, analysis: Analysis) -> None:
    """Say first that the answers are not people's answers to the study, when they are not."""
    if analysis.origin == "pilot":
        doc.banner(
            "PILOT DATA",
            "These answers were recorded by a pilot build of the study pages (human samples "
            "stood in for by copies of the robot's writing): they try out the pages and the "
            "analysis and say nothing about the robot's handwriting.",
        )
    elif analysis.origin == "simulated":
        from studies.analysis.truth import describe

        known = [
            f"{st.kind}: {describe(st.truth)} (`{st.truth_path}`)"
            for st in analysis.studies
            if st.truth is not None
        ]
        missing = [st.kind for st in analysis.studies if st.truth is None]
        drawn = "drawn by `prg-study simulate`"
        if known:
            drawn += (
                f" from a known truth ({'; '.join(known)}); each estimate below is shown "
                "beside the true value it should recover."
            )
        if missing:
            drawn += (
                f"{' The' if known else '; the'} truth of {', '.join(missing)} (its "
                "`<name>.truth.json`, or `--truth`) was not found, so its estimates cannot be "
                "compared with it."
            )
        doc.banner(
            "SIMULATED DATA",
            f"These are simulated participants, not people: {drawn} The verdicts test the "
            "analysis, not the robot's handwriting.",
        )


def build_report(analysis: Analysis, reproduced: pd.DataFrame | None = None) -> Doc:
    """The report as a :class:`Doc` (render with ``.markdown()`` / ``.html()``)."""
    name = analysis.config.name
    file = Path(analysis.source).name
    title = f"User-study analysis: {name} ({file})" if name else f"User-study analysis: {file}"
    doc = Doc(title + ORIGIN_TITLES.get(analysis.origin, ""))
    _origin_banner(doc, analysis)
    doc.h(2, "Summary")
    doc.ul([line for st in analysis.studies for line in st.conclusions])
    for st in analysis.studies:
        if st.truth is not None:
            from studies.analysis.truth import headline

            doc.table(
                headline(st),
                f"{st.kind}: the main estimates beside the simulation's truth (every table "
                "below has a truth column too).",
            )
    doc.h(2, "Data")
    att = analysis.attention
    failed = att.loc[att["failed_any"], "participant_id"].tolist()
    items = [
        f"File `{analysis.source}`: {analysis.rows_in_file} rows, {att['participant_id'].nunique()} participants.",
        f"Attention checks: {int(att['checks'].sum())} check trials; {len(failed)} participants failed at least one"
        + (
            f" ({', '.join(map(str, failed[:10]))}{' ...' if len(failed) > 10 else ''})."
            if failed
            else "."
        ),
    ]
    items += [
        f"Analysed ({st.kind}): {st.data['participant_id'].nunique()} participants, {len(st.data)} trials."
        for st in analysis.studies
    ]
    items += analysis.notes
    doc.ul(items)
    for st in analysis.studies:
        (_study1_section if st.kind == TURING else _study2_section)(doc, st)
    _paper_section(doc, reproduced, analysis)
    _methods(doc, analysis)
    return doc


def _csv(frames: list[pd.DataFrame], path: Path) -> None:
    frames = [f for f in frames if f is not None and not f.empty]
    (pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()).to_csv(path, index=False)


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


def check_out_dir(out: str | Path) -> Path:
    """``out`` as a Path, if it is new, empty or an earlier report folder (else UsageError)."""
    out = Path(out)
    if out.exists() and (
        not out.is_dir() or (any(out.iterdir()) and not (out / "report.md").exists())
    ):
        raise UsageError(
            f"--out {out}: exists and is not an earlier report folder; choose a new or empty folder"
        )
    return out


def judge_section(doc: Doc, judge: dict) -> None:
    """What the automatic judge (``prg-study judge``, :mod:`studies.judge`) said of the study's
    stimuli before any participant saw them."""
    doc.h(2, "Before the participants: the automatic judge")
    obs = judge["observer"]
    doc.p(
        f"`prg-study judge` on `{judge['folder']}`: {judge['words']} words, "
        f"{judge['robot_samples']} robot and {judge['human_samples']} human samples. A linear "
        "classifier trained leaving one word out tells the robot's words from the people's "
        "(balanced accuracy, 0.5: indistinguishable); a simulated observer picks the robot among "
        f"{judge['n_options']} (chance {judge['chance']:.2f}, the paper's participants "
        f"{judge['paper_participants']:.2f})."
    )
    rows = [
        {
            "measure": f"C2ST, {name}",
            "value": f"{c['balanced_accuracy']:.2f}",
            "95 % CI": f"{c['ci95'][0]:.2f}-{c['ci95'][1]:.2f}",
        }
        for name, c in judge["c2st"].items()
    ]
    rows.append(
        {
            "measure": "simulated observer's pick rate",
            "value": f"{obs['pick_rate']:.2f}",
            "95 % CI": f"{obs['ci95'][0]:.2f}-{obs['ci95'][1]:.2f}",
        }
    )
    doc.table(pd.DataFrame(rows), "The judge's scores (95 % intervals by bootstrapping the words).")


def write_report(
    analysis: Analysis, out: str | Path, *, paper: bool = True, judge: dict | None = None
) -> Path:
    """Write the report folder atomically (see the module docstring); returns ``out``.
    ``judge``: a ``judge.json`` (:func:`studies.judge.judge`) to report beside the analysis.

    Raises
    ------
    prg.errors.UsageError
        ``out`` exists, is not empty and does not hold an earlier report.
    """
    out = check_out_dir(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    from studies.analysis.paper import reproduce_paper

    reproduced = reproduce_paper() if paper else None
    doc = build_report(analysis, reproduced)
    if judge is not None:
        judge_section(doc, judge)
    with staged_folder(out) as tmp:
        (tmp / "figures").mkdir()
        for b in doc.blocks:
            if b[0] == "fig":
                (tmp / "figures" / b[1]).write_bytes(b[2])
        (tmp / "report.md").write_text(doc.markdown(), encoding="utf-8")
        (tmp / "report.html").write_text(doc.html(), encoding="utf-8")
        tests = []
        for st in analysis.studies:
            tests.append(st.tests)
        _csv(tests, tmp / "tests.csv")
        _csv([st.per_word for st in analysis.studies], tmp / "per_word.csv")
        parts = []
        for st in analysis.studies:
            pp = st.per_participant.merge(
                analysis.attention.rename(
                    columns={"checks": "attention_checks", "failed": "attention_failed"}
                )[["participant_id", "study", "attention_checks", "attention_failed"]],
                on=["participant_id", "study"],
                how="left",
            ).assign(excluded=False)
            parts.append(pp)
        excluded = analysis.attention[analysis.attention["failed_any"]]
        if len(excluded) and analysis.config.exclude_failed_attention:
            parts.append(
                excluded.rename(
                    columns={"checks": "attention_checks", "failed": "attention_failed"}
                )[["study", "participant_id", "attention_checks", "attention_failed"]].assign(
                    excluded=True
                )
            )
        _csv(parts, tmp / "per_participant.csv")
        _csv(
            [
                st.mixed.assign(study=st.kind)
                for st in analysis.studies
                if st.mixed is not None and len(st.mixed)
            ],
            tmp / "mixed_model.csv",
        )
        if reproduced is not None:
            reproduced.to_csv(tmp / "paper_reproduction.csv", index=False)
        metrics = {
            "source": analysis.source,
            "origin": analysis.origin,
            "truth": {st.kind: st.truth.to_dict() for st in analysis.studies if st.truth},
            "studies": {st.kind: _jsonable(st.verdict) for st in analysis.studies},
            "warnings": [w for st in analysis.studies for w in st.warnings],
        }
        if judge is not None:
            metrics["judge"] = {
                "observer_pick_rate": judge["observer"]["pick_rate"],
                "observer_ci95": judge["observer"]["ci95"],
                "c2st": {k: v["balanced_accuracy"] for k, v in judge["c2st"].items()},
            }
        (tmp / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n", encoding="utf-8")
    return out


__all__ = ["Doc", "build_report", "check_out_dir", "fmt_p", "tests_table", "write_report"]
