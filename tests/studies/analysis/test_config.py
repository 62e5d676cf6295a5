"""The response schema, the checked reader (one clear line per problem), attention checks and the
analysis options read from the study YAML."""

from __future__ import annotations

import pytest

from prg.errors import UsageError
from studies.analysis.config import AnalysisSettings, load_config, with_overrides
from tests.helpers.study_analysis_validate import REPO
from tests.helpers.study_design import REPO

# --------------------------------------------------------------------------- options


def test_config_reads_the_known_keys_top_level_and_under_analysis(tmp_path):
    p = tmp_path / "t.yaml"
    p.write_text(
        "name: turing\nkind: turing\nfoils: 3\nequivalence_margin: 0.04\nalpha: 0.01\n"
        "words: [a, b]\nrender: {width_px: 720}\nanalysis:\n  margin_source: data\n"
    )
    cfg = load_config(p)
    assert (cfg.kind, cfg.margin, cfg.alpha, cfg.n_options, cfg.chance) == (
        "turing",
        0.04,
        0.01,
        4,
        0.25,
    )
    assert cfg.margin_source == "data" and cfg.words == ("a", "b")


def test_config_margin_without_source_is_unstated_and_noted(tmp_path):
    p = tmp_path / "t.yaml"
    p.write_text("kind: readability\nequivalence_margin: 0.1\n")
    cfg = load_config(p)
    assert cfg.margin_source == "unstated" and "no margin_source" in cfg.notes[0]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("kind: movie\n", "kind 'movie' is not one of turing, readability"),
        ("equivalence_margin: 1.5\n", r"equivalence_margin 1.5 is outside \(0, 1\)"),
        ("alpha: lots\n", "alpha 'lots' is not a number"),
        ("margin_source: vibes\n", "margin_source 'vibes' is not one of preregistered, data"),
        ("- a\n- b\n", "expected a mapping of keys"),
        ("a: [1, 2\n", "not valid YAML"),
    ],
)
def test_bad_config_values_name_the_file_and_key(tmp_path, text, message):
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    with pytest.raises(UsageError, match=rf"^{p}.*{message}"):
        load_config(p)


def test_command_line_overrides_are_checked_and_mark_the_margin_unstated():
    cfg = with_overrides(
        AnalysisSettings(margin=0.05, margin_source="preregistered"), margin=0.08, alpha=0.1
    )
    assert (cfg.margin, cfg.alpha, cfg.margin_source) == (0.08, 0.1, "unstated")
    with pytest.raises(UsageError, match=r"--alpha 0.7 is outside"):
        with_overrides(AnalysisSettings(), alpha=0.7)


def test_the_study_configs_in_conf_read_as_their_kind():
    for kind in ("turing", "readability"):
        cfg = load_config(REPO / "conf" / "study" / f"{kind}.yaml")
        assert cfg.kind == kind and 0 < cfg.margin_for(kind) < 0.5 and 0 < cfg.alpha < 0.5


def test_the_analysis_reads_the_same_study_files():
    from studies.analysis.config import load_config

    for name, kind, margin in (("turing", "turing", 0.05), ("readability", "readability", 0.10)):
        cfg = load_config(REPO / f"conf/study/{name}.yaml")
        assert (cfg.kind, cfg.margin, cfg.margin_source) == (kind, margin, "preregistered")
