"""`benchmarks/summarize.py`: the result tables of `benchmarks/results.md` and of the docs pages
(`docs/results.md`, `docs/benchmarks.md`) come from the JSON, and stay in step."""

import importlib.util
import json
import math
import shutil
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("bench_summarize", ROOT / "benchmarks/summarize.py")
summarize = sys.modules["bench_summarize"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(summarize)


def test_results_md_and_the_docs_pages_match_the_committed_json(capsys):
    code = summarize.main(["--check"])
    assert code == 0, capsys.readouterr().err


def test_the_docs_pages_hold_the_generated_blocks():
    assert {
        p.relative_to(summarize.ROOT).as_posix(): names for p, names in summarize.BLOCKS.items()
    } == {
        "docs/results.md": ("demo", "converged", "baselines"),
        "docs/benchmarks.md": ("benchmarks",),
    }


def test_check_names_each_stale_page_on_one_line_and_a_run_refreshes_them(
    tmp_path, monkeypatch, capsys
):
    outputs = sys.modules[summarize.main.__module__]
    pages = {}
    for path, names in summarize.BLOCKS.items():
        page = tmp_path / path.name
        page.write_text(
            "# a page\n\n"
            + "".join(f"<!-- generated:{n} -->\nold\n<!-- end:{n} -->\n" for n in names)
        )
        pages[page] = names
    summary = tmp_path / "summary.md"
    summary.write_text(summarize.results_markdown())
    monkeypatch.setattr(outputs, "BLOCKS", pages)
    monkeypatch.setattr(outputs, "SUMMARY", summary)
    assert summarize.main(["--check"]) == 1
    stale = capsys.readouterr().err.splitlines()
    assert stale == [f"summarize: {page} is stale: run `make results`" for page in pages]
    assert summarize.main([]) == 0
    assert summarize.main(["--check"]) == 0
    benchmarks, results = (
        (tmp_path / "benchmarks.md").read_text(),
        (tmp_path / "results.md").read_text(),
    )
    assert benchmarks.startswith("# a page\n\n<!-- generated:benchmarks -->\nRatio = ours / ")
    assert summarize.demo_markdown() in results and summarize.converged_markdown() in results
    assert "\nold\n" not in results + benchmarks


def test_every_benchmark_json_gives_rows_with_a_reference_and_a_finite_ratio():
    rows = summarize.benchmark_rows()
    on_disk = {p.stem for p in summarize.RESULTS.glob("bench_*.json")}
    assert set(rows) == on_disk == set(summarize.BENCHMARKS)
    for name, items in rows.items():
        assert items, name
        for row in items:
            assert row.reference and row.reference_value and row.ours
            if row.ours.startswith("not reached"):  # no time of ours to compare
                assert math.isnan(row.ratio), (name, row)
            else:
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
    with pytest.raises(
        summarize.SummaryError, match=r"docs/results\.md: no <!-- generated:demo -->"
    ):
        summarize.fill_block("# a page without blocks\n", "demo", "x", "docs/results.md")
    page = tmp_path / "results.md"
    page.write_text("<!-- generated:demo -->\n<!-- end:demo -->\n")  # no converged block
    with pytest.raises(summarize.SummaryError, match=r"results\.md: no <!-- generated:converged"):
        summarize.docs_texts({page: ("demo", "converged")})
    with pytest.raises(summarize.SummaryError, match=r"absent\.md: not readable"):
        summarize.docs_texts({tmp_path / "absent.md": ("demo",)})
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


def test_speed_techniques_and_time_to_quality_become_rows_against_their_references(tmp_path):
    results = tmp_path / "results"
    shutil.copytree(summarize.RESULTS, results)
    data = json.loads((results / "bench_train.json").read_text())
    data["techniques"] = {
        "family": "muse",
        "reference": "fp32, batch 64 (paper)",
        "techniques": {
            "fp32, batch 64 (paper)": {"samples_per_s": 400.0},
            "batch 128 + bf16 autocast": {"samples_per_s": 1000.0},
        },
    }
    ours = {
        "profile": "quick",
        "cpu_min_to": {"imputed": {"0.6": 2.0, "0.7": 6.0}, "mean": {}},
        "cpu_min_spent": 9.0,
    }
    paper = {
        "profile": "paper",
        "cpu_min_to": {"imputed": {"0.6": 20.0}, "mean": {}},
        "cpu_min_spent": 30.0,
    }
    data["time_to_quality"] = {
        "target": 0.85,
        "levels": [0.6, 0.7, 0.8, 0.85],
        "ours": ours,
        "paper": paper,
        "speedup": {
            "imputed": {
                "0.6": {"ratio": 10.0, "lower_bound": False},
                "0.7": {"ratio": 5.0, "lower_bound": True},
            },
            "mean": {},
        },
    }
    (results / "bench_train.json").write_text(json.dumps(data))
    rows = summarize.benchmark_rows(results)["bench_train"]
    (bf16,) = [r for r in rows if "bf16" in r.figure]
    assert (bf16.ours, bf16.reference_value, bf16.ratio) == (
        "1,000 samples/s",
        "400 samples/s",
        2.5,
    )
    quality = {
        tuple(r.figure.split()[6:9:2]): r for r in rows if r.figure.startswith("CPU time to MUSE")
    }
    assert list(quality) == [  # 0.8: reached by neither; the mean decoding: only the target
        ("0.6", "imputed"),
        ("0.7", "imputed"),
        ("0.85", "imputed"),
        ("0.85", "mean"),
    ]
    quality = {level: r for (level, decoding), r in quality.items() if decoding == "imputed"}
    assert (quality["0.6"].ours, quality["0.6"].reference_value) == ("2.0 CPU min", "20.0 CPU min")
    assert quality["0.6"].ratio == pytest.approx(0.1) and "upper bound" not in quality["0.6"].figure
    assert quality["0.7"].reference_value == "not reached in 30.0 CPU min"
    assert quality["0.7"].ratio == pytest.approx(0.2) and "upper bound" in quality["0.7"].figure
    assert quality["0.85"].ours == "not reached in 9.0 CPU min"
    assert math.isnan(quality["0.85"].ratio) and summarize.ratio_text(quality["0.85"].ratio) == "-"


def _converged_root(tmp_path, status: str = "ok") -> Path:
    root = tmp_path / "converged"
    for name, relative in summarize.CONVERGED_SOURCES.items():
        if name == "run.json":
            continue
        (root / relative).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(summarize.DEMO / name, root / relative)
    fit = {"fit_cpu_s": 600.0, "fit_wall_s": 400.0, "epochs": 7.0, "steps": 3800.0}
    run = {
        "status": status,
        "profile": "converged",
        "command": "python -m prg.commands.paper_scale --profile converged --device auto",
        "device": "a test CPU",
        "cpu_count": 2,
        "total_seconds": 3000.0,
        "settings": {
            "k_marginal": 1000,
            "k_conditional": 5000,
            "n_test": None,
            "n_test_likelihood": 100,
        },
        "fit": {"muse": fit},
        "stages": {
            "train": {"seconds": 1800.0},
            "evaluate": {"seconds": 1200.0},
        },
    }
    (root / "reports/paper_scale.json").write_text(json.dumps(run))
    return root


def test_the_converged_snapshot_shows_its_command_costs_and_tables(tmp_path):
    out = tmp_path / "snapshot"
    assert "No converged snapshot yet" in summarize.converged_markdown(out)
    summarize.snapshot_converged(_converged_root(tmp_path), out)
    text = summarize.converged_markdown(out)
    assert "`python -m prg.commands.paper_scale --profile converged --device auto`" in text
    assert "PRG_MUSE(T,S,I) 10.0 min CPU (7 epochs)" in text
    assert "on 100 test samples for Table I and all for coherence" in text
    assert TABLE1 in text and COHERENCE in text and "**Missing-modality robustness**" in text


def test_an_unfinished_converged_run_is_not_snapshotted(tmp_path):
    with pytest.raises(summarize.SummaryError, match="not a finished converged run"):
        summarize.snapshot_converged(_converged_root(tmp_path, "failed: x"), tmp_path / "s")
    assert not (tmp_path / "s").exists()


def test_robustness_shows_folded_trajectory_coherence_for_each_input_subset(tmp_path):
    text = _demo_with(
        tmp_path,
        {"muse/coherence_folded_T_given_SI": 0.91, "muse/coherence_folded_T_given_TSI": 0.97},
    )
    robustness = _row(text, "**Missing-modality robustness**", "PRG_MUSE(T,S,I)")
    assert robustness == ["-", "-", "91%", "-", "-", "-", "97%"]


def test_muse_imputed_rows_follow_its_posterior_mean_rows(tmp_path):
    text = _demo_with(
        tmp_path,
        {
            "muse/coherence_T_given_S": 0.68,
            "muse/coherence_folded_T_given_S": 0.68,
            "muse/coherence_imputed_T_given_S": 0.9,
            "muse/coherence_folded_imputed_T_given_S": 0.94,
            "muse/roughness_ratio_imputed_T_given_S": 1.1,
        },
    )
    assert _row(text, COHERENCE, "PRG_MUSE(T,S,I)")[0] == "68% / 68%"
    assert _row(text, COHERENCE, "PRG_MUSE(T,S,I), imputed")[0] == "90% / 94%"
    assert _row(text, SMOOTHNESS, "PRG_MUSE(T,S,I), imputed") == ["1.10", "-"]
    assert "PRG_AVAE(T,S), imputed" not in text


def test_images_moved_off_centre_show_each_shift_for_the_models_that_read_images(tmp_path):
    values = {
        f"{f}/coherence_folded_{c}_shift{s}": v
        for f, c, v0 in (
            ("muse", "T_given_I", 0.9),
            ("muse", "S_given_I", 0.8),
            ("avae_ti", "T_given_I", 0.7),
        )
        for s, v in ((0, v0), (1, v0 - 0.1), (2, v0 - 0.2))
    }
    text = _demo_with(tmp_path, values)
    title = "**Images moved off-centre**"
    assert _row(text, title, "PRG_MUSE(T,S,I)") == ["90%", "80%", "70%", "80%", "70%", "60%"]
    assert _row(text, title, "PRG_AVAE(T,I)") == ["70%", "60%", "50%", "-", "-", "-"]
    assert "PRG_CVAE(T,S)" not in text.split(title)[1].split("**Smoothness**")[0]
    assert title not in _demo_with(tmp_path / "old", {})  # a snapshot made before it: no table


def test_the_baselines_snapshot_shows_its_tables_over_seeds_and_its_wall_time(tmp_path):
    from prg.evaluation import seed_report, seeds
    from tests.helpers.seeds import seed_sweep

    out = tmp_path / "snapshot"
    assert "No baselines snapshot yet" in summarize.baselines_markdown(out)
    sweep = seed_sweep(tmp_path / "baselines", ["cvae", "avae_ti"], [0, 1, 2])
    agg = {
        **seeds.aggregate(seeds.collect(sweep)),
        "wall_min": 12.5,
        "machine": "a CPU (2 cores)",
    }
    (sweep / "report").mkdir(parents=True)
    (sweep / "report" / "aggregate.json").write_text(json.dumps(seeds.json_ready(agg)))
    summarize.snapshot_baselines(sweep, out)
    text = summarize.baselines_markdown(out)
    assert "`cvae`, `avae_ti` x seeds 0-2 (quick profile), 12.5 min wall on a CPU (2 cores)" in text
    # cvae's coherence over seeds 0-2 (tests/helpers/seeds.py: 0.5 + 0.01 s)
    assert "| `coherence_T_given_S` |" in text and "0.510 [" in text
    # the docs' block is the whole aggregate's summary, from the cut-down copy
    whole = seed_report.summary_markdown(
        json.loads(json.dumps(seeds.json_ready(agg))), heading="###"
    )
    assert text.endswith(whole.rstrip("\n"))
    # the per-seed metrics came along: aggregated again, they give the same summary
    copied = sorted(p.relative_to(out / "seeds") for p in (out / "seeds").rglob("*.json"))
    assert len(copied) == 3 * 2 * 3
    again = seeds.json_ready(seeds.aggregate(seeds.collect(out / "seeds")))
    assert seed_report.summary_markdown(again) == seed_report.summary_markdown(
        json.loads((out / "aggregate.json").read_text())
    )
    # an aggregate without its inputs, or not an aggregate, is refused, the snapshot kept
    shutil.rmtree(sweep / "seed2" / "reports" / "avae_ti")  # a pair not evaluated: left out
    summarize.snapshot_baselines(sweep, out)
    assert len(list((out / "seeds").rglob("*.json"))) == 15
    assert not (out / "seeds" / "seed2" / "reports" / "avae_ti").exists()
    (sweep / "seed1" / "reports" / "cvae" / "timing.json").unlink()
    with pytest.raises(summarize.SummaryError, match=r"seed1/reports/cvae/timing.json does not"):
        summarize.snapshot_baselines(sweep, out)
    assert len(list((out / "seeds").rglob("*.json"))) == 15
    (sweep / "report" / "aggregate.json").write_text("{}")
    with pytest.raises(summarize.SummaryError, match="not an aggregate"):
        summarize.snapshot_baselines(sweep, out)


def test_a_snapshot_whose_families_have_different_seeds_says_so(tmp_path):
    from prg.evaluation import seeds

    values = {
        "cvae": {"coherence_T_given_S": {0: 0.80, 1: 0.82, 2: 0.79}},
        "mvae": {"coherence_T_given_S": {0: 0.40}},  # a run stopped after seed 0 of mvae
    }
    agg = seeds.json_ready(seeds.aggregate(values))
    (tmp_path / "aggregate.json").write_text(json.dumps(agg))
    text = summarize.baselines_markdown(tmp_path)
    assert "x seeds 0-2 (not every family on each: each table's Seeds line says which)" in text
    assert "Seeds: PRG_CVAE(T,S) 3 (0-2); MVAE(T,S,I) 1 (0)." in text
    assert "1 untested (fewer than two seeds in common, or the same difference" in text
