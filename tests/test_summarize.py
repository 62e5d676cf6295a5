"""`benchmarks/summarize.py`: the README's result tables come from the JSON, and stay in step."""

import importlib.util
import json
import shutil
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("bench_summarize", ROOT / "benchmarks/summarize.py")
summarize = sys.modules["bench_summarize"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(summarize)


def test_results_md_and_readme_match_the_committed_json(capsys):
    code = summarize.main(["--check"])
    assert code == 0, capsys.readouterr().err


def test_every_benchmark_json_gives_rows_with_a_reference_and_a_finite_ratio():
    rows = summarize.benchmark_rows()
    on_disk = {p.stem for p in summarize.RESULTS.glob("bench_*.json")}
    assert set(rows) == on_disk == set(summarize.BENCHMARKS)
    for name, items in rows.items():
        assert items, name
        for row in items:
            assert row.reference and row.reference_value and row.ours
            assert row.ratio > 0 and row.ratio < float("inf"), (name, row)


def test_a_changed_measurement_changes_the_table(tmp_path):
    results = tmp_path / "results"
    shutil.copytree(summarize.RESULTS, results)
    data = json.loads((results / "bench_train.json").read_text())
    data["families"]["muse"]["lightning_samples_per_s"] = 12_345.0
    data["families"]["muse"]["plain_samples_per_s"] = 24_690.0
    (results / "bench_train.json").write_text(json.dumps(data))
    table = summarize.benchmarks_markdown(results)
    (line,) = [x for x in table.splitlines() if "throughput, muse" in x]
    assert "12,345 samples/s" in line and "24,690 samples/s" in line and "| 0.5 |" in line
    assert "muse 0.1 h" in table  # the paper-profile estimate follows the throughput


def test_snapshot_copies_the_demo_metrics_with_their_dvc_hashes(tmp_path):
    lock = {"schema": "2.0", "stages": {}}
    for i, (name, source) in enumerate(summarize.DEMO_SOURCES.items()):
        path = tmp_path / source
        path.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(summarize.DEMO / name, path)
        out = str(Path(source).parent) if name == "dictaphone.json" else source
        lock["stages"][f"s{i}"] = {"outs": [{"path": out, "md5": f"{i:032x}"}]}
    (tmp_path / "dvc.lock").write_text(json.dumps(lock))  # JSON is YAML
    demo = tmp_path / "snapshot"
    summarize.snapshot(tmp_path, demo)
    provenance = json.loads((demo / "provenance.json").read_text())
    assert provenance["dictaphone.json"]["dvc_out"] == "reports/dictaphone"
    assert all(p["dvc_md5"] for p in provenance.values())
    assert summarize.demo_markdown(demo) == summarize.demo_markdown(summarize.DEMO)


def test_bad_inputs_are_named(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    (results / "bench_dmp.json").write_text("{not json")
    with pytest.raises(summarize.SummaryError, match=r"bench_dmp\.json: not readable JSON"):
        summarize.benchmark_rows(results)
    (results / "bench_dmp.json").write_text("{}")
    with pytest.raises(summarize.SummaryError, match=r"bench_dmp\.json: unexpected content"):
        summarize.benchmark_rows(results)
    with pytest.raises(summarize.SummaryError, match="no <!-- generated:demo -->"):
        summarize.fill_block("# README without blocks\n", "demo", "x")
    with pytest.raises(summarize.SummaryError, match="missing"):
        summarize.demo_markdown(tmp_path)


def _row(text: str, after: str, model: str) -> list[str]:
    """The cells of ``model``'s row in the first table after the text ``after``."""
    lines = text.split(after, 1)[1].splitlines()
    first = next(i for i, x in enumerate(lines) if x.startswith("|"))
    table = lines[first : next((i for i in range(first, len(lines)) if not lines[i]), None)]
    (line,) = [x for x in table if x.startswith(f"| {model} ")]
    return [c.strip() for c in line.strip("|").split("|")][1:]


def _demo_with(tmp_path, evaluate: dict) -> str:
    demo = tmp_path / "demo"
    shutil.copytree(summarize.DEMO, demo)
    kept = json.loads((demo / "evaluate.json").read_text())
    kept = {k: v for k, v in kept.items() if k.startswith("classifier/")}
    (demo / "evaluate.json").write_text(json.dumps({**kept, **evaluate}))
    return summarize.demo_markdown(demo)


TABLE1 = "**Table I**"
OWN = "The trajectory cells under each model's own std"
COHERENCE = "**Cross-modal coherence**"
SMOOTHNESS = "**Smoothness**"


def test_demo_tables_show_the_paper_convention_folded_coherence_and_roughness(tmp_path):
    text = _demo_with(
        tmp_path,
        {
            "avae_ts/logp_T": -196.61,
            "avae_ts/logp_T_model_std": 206.16,
            "avae_ts/logp_S": -5.21,
            "avae_ts/coherence_T_given_S": 0.7258,
            "avae_ts/coherence_folded_T_given_S": 0.8012,
            "avae_ts/roughness_ratio_T_given_S": 1.234,
            "test_split/roughness": 0.0814,
        },
    )
    # T, S, I, T|S, T|I, S|T, I|T, val loss: ours (paper)
    assert _row(text, TABLE1, "PRG_AVAE(T,S)")[:2] == ["-196.6 (-197.55)", "-5.2 (-4.17)"]
    assert _row(text, OWN, "PRG_AVAE(T,S)")[0] == "206.2"
    assert _row(text, OWN, "PRG_MUSE(T,S,I)") == ["-", "-", "-"]  # missing: '-'
    assert _row(text, COHERENCE, "PRG_AVAE(T,S)")[0] == "73% / 80%"
    assert _row(text, SMOOTHNESS, "PRG_AVAE(T,S)") == ["1.23", "-"]
    assert "(0.081)" in text.split(SMOOTHNESS)[1]
    assert "predates" not in text


def test_an_old_snapshot_shows_its_trajectory_cells_only_under_the_models_own_std(tmp_path):
    """Before the two conventions, `logp_T*` held the models' own std (0.1)."""
    text = _demo_with(
        tmp_path,
        {"avae_ts/logp_T": 206.16, "avae_ts/logp_S": -5.21, "avae_ts/coherence_T_given_S": 0.7},
    )
    assert _row(text, TABLE1, "PRG_AVAE(T,S)")[:2] == ["-", "-5.2 (-4.17)"]
    assert _row(text, OWN, "PRG_AVAE(T,S)")[0] == "206.2"
    assert "predates the unit-variance table" in text.split(OWN)[0]
    assert _row(text, COHERENCE, "PRG_AVAE(T,S)")[0] == "70% / -"
