"""Tests of ``prg.evaluation.reports`` (moved from the suite on: report text of `prg-evaluate` from
hand-made result rows: Table I's two trajectory conventions, exact and folded coherence, the
smoothness section, the metric keys)."""

from prg.evaluation.reports import (
    coherence_markdown,
    robustness_markdown,
    table1_markdown,
)
from tests.helpers.reports import COHERENCE, SMOOTHNESS, _lk

OWN_SECTION = "## Trajectory cells under each model's own std"


def _table_line(text: str, start: str) -> str:
    (line,) = [x for x in text.splitlines() if x.startswith(start)]
    return line


def test_table1_shows_the_main_convention_and_the_models_own_std_below():
    rows = [
        _lk("logp_T", -196.61, std=1.0),
        _lk("logp_T_model_std", 206.16, std=0.1),
        _lk("logp_S", -5.21),
        _lk("logp_T_given_S", -190.42, std=1.0),
        _lk("logp_T_given_S_model_std", 32.99, std=0.1),
    ]
    text = table1_markdown(rows, "setup line", 1.0)
    main, own = text.split(OWN_SECTION)
    line = _table_line(main, "| PRG_AVAE(T,S)")
    cells = [c.strip() for c in line.strip("|").split("|")]
    # model, T, S, I, T|S, T|I, S|T, I|T
    assert cells[1] == "-196.61 ± 0.50 (-197.55)"
    assert cells[2] == "-5.21 ± 0.50 (-4.17)"
    assert cells[4] == "-190.42 ± 0.50 (-189.28)"
    assert "206.16" not in main.split("Density convention")[0]
    own_line = _table_line(own, "| PRG_AVAE(T,S)")
    own_cells = [c.strip() for c in own_line.strip("|").split("|")]
    assert own_cells == ["PRG_AVAE(T,S)", "0.1", "206.16 ± 0.50", "32.99 ± 0.50", "-"]
    assert "-197.55" not in own_line  # paper values belong to the unit-variance table
    assert "unit variance" in text
    # the note explains why the paper's log p(x_S | x_T) is positive
    assert "impossible for a normalised categorical" in text
    assert "1.94" in text.split("Density convention")[1]


def test_table1_without_model_std_rows_has_no_second_table_and_names_its_convention():
    text = table1_markdown([_lk("logp_S", -5.0)], "setup", None)
    assert OWN_SECTION not in text
    assert "each model's own std per coordinate" in text


CLASSIFIERS = {"traj": {"test_accuracy": 0.9, "test_folded_accuracy": 0.97}}


def test_coherence_report_has_exact_and_folded_columns_and_the_smoothness_section():
    text = coherence_markdown(COHERENCE, CLASSIFIERS, "setup", SMOOTHNESS)
    assert "| generated | mean | mean, folded | sampled | sampled, folded |" in text
    assert _table_line(text, "| T given {S} |") == "| T given {S} | 0.512 | 0.688 | 0.312 | 0.438 |"
    smooth = text.split("## Smoothness of decoded letters")[1]
    assert "arc length" in smooth and "0.200" in smooth  # the definition, the test median
    assert _table_line(smooth, "| PRG_MUSE") == "| PRG_MUSE(T,S,I) | T given {S} | 0.432 | 2.16 |"
    assert "Smoothness" not in coherence_markdown(COHERENCE, CLASSIFIERS, "setup")


def test_robustness_shows_folded_in_parentheses():
    text = robustness_markdown(COHERENCE, "mean", "setup")
    assert _table_line(text, "| PRG_MUSE") == "| PRG_MUSE(T,S,I) | 0.512 (0.688) | 0.875 (0.900) |"


def test_coherence_report_shows_both_classifiers_and_their_agreement():
    second = {
        "coherence_second": 0.25,
        "coherence_folded_second": 0.3751,
        "agreement": 0.4,
        "agreement_folded": 0.5012,
        "difference": 0.2624,
        "difference_folded": 0.3125,
        "coherence_folded_both": 0.2987,
    }
    rows = [{**row, **second} for row in COHERENCE]
    rows.append(
        {**COHERENCE[0], "target": "label", "given": "T", **dict.fromkeys(second)}  # no 2nd
    )
    info = {
        **CLASSIFIERS,
        "traj_rendered": {"test_accuracy": 0.8123, "reader": "second: drawn"},
    }
    text = coherence_markdown(rows, info, "setup")
    assert "- traj_rendered (second: drawn): test accuracy 0.812" in text
    section = text.split("## Two classifiers: agreement")[1]
    line = _table_line(section, "| T given {S} |")
    assert line.count("0.688 / 0.375 (agree 0.50, both 0.30)") == 1  # mean
    assert "0.438 / 0.375" in line  # sampled: the first classifier's own folded rate
    assert "S given" not in section  # a generated label has no second reading
    assert "| T given {S} | 0.512 | 0.688 † |" in text  # first classifier, disagreement marked
    assert "Two classifiers" not in coherence_markdown(COHERENCE, CLASSIFIERS, "setup")
