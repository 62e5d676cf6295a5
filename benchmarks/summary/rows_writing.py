"""Rows of the benchmarks on the writing side: DMPs (synthetic and LASA), whole words, the
connections between letters, the pen's kinematics, and the simulated robots."""

from __future__ import annotations

from .common import Row


def dmp_rows(d: dict) -> list[Row]:
    target = f"<= {1 / d['settings']['target_ratio']:.2g}"
    rows = []
    for r in d["rows"]:
        ours = r["ours_fit_ms"] + r["ours_rollout_ms"]
        theirs = r["theirs_fit_ms"] + r["theirs_rollout_ms"]
        rows.append(
            Row(
                f"DMP fit + rollout, {r['points']} points, {r['basis']} bases",
                f"{ours:.1f} ms (RMSE {10 * r['ours_rmse_cm']:.2g} mm)",
                "movement-primitives",
                f"{theirs:.1f} ms (RMSE {10 * r['theirs_rmse_cm']:.2g} mm)",
                ours / theirs,
                target,
            )
        )
    for r in d["equal_error"]:
        rows.append(
            Row(
                f"DMP at equal error, {r['points']} points",
                f"{r['ours_ms']:.1f} ms ({r['ours_basis']} bases)",
                "movement-primitives",
                f"{r['theirs_ms']:.1f} ms ({r['theirs_basis']} bases)",
                r["ours_ms"] / r["theirs_ms"],
                target,
            )
        )
    return rows


def lasa_rows(d: dict) -> list[Row]:
    speed = f"<= {1 / d['settings']['target_ratio']:.2g}"
    rows = []
    for r in d["rows"]:
        rows.append(
            Row(
                f"DMP on LASA, {r['demos']} human demonstrations, {r['basis']} bases: "
                "fit + rollout (median)",
                f"{r['ours_ms']:.1f} ms",
                "movement-primitives",
                f"{r['theirs_ms']:.1f} ms",
                r["ours_ms"] / r["theirs_ms"],
                speed,
            )
        )
        for kind in ("median", "worst"):
            rows.append(
                Row(
                    f"DMP on LASA, {r['basis']} bases: RMSE {kind} (at rest: "
                    f"{r[f'rest_rmse_{kind}_mm']:.3g} mm)",
                    f"{r[f'ours_rmse_{kind}_mm']:.3g} mm",
                    "movement-primitives",
                    f"{r[f'theirs_rmse_{kind}_mm']:.3g} mm",
                    r[f"ours_rmse_{kind}_mm"] / r[f"theirs_rmse_{kind}_mm"],
                    f"<= 1 on every demonstration ({r['demos'] - len(r['ours_worse_than_theirs'])}"
                    f" of {r['demos']})"
                    if kind == "worst"
                    else "",
                )
            )
    return rows


def write_rows(d: dict) -> list[Row]:
    target_ms = d["settings"]["target_ms_6_letters"]
    rows = [
        Row(
            f"write a {r['letters']}-letter word, {r['family']} (label -> DMP rollout)",
            f"{r['total_ms']:.1f} ms",
            "straight-line joiner",
            f"{r['straight_ms']:.1f} ms",
            r["total_ms"] / r["straight_ms"],
            f"<= {target_ms:.0f} ms" if r["letters"] == 6 else "",
        )
        for r in d["rows"]
        if r["letters"] in (1, 6, 12)
    ]
    worst = max(r["max_rmse_mm"] for r in d["rows"])
    target_mm = d["settings"]["target_rmse_mm"]
    rows.append(
        Row(
            "DMP reproduction error, worst word",
            f"{worst:.3f} mm",
            "target",
            f"{target_mm} mm",
            worst / target_mm,
            "<= 1",
        )
    )
    target_ratio = d["settings"].get("target_speech_ratio")
    for r in d.get("speech", []):
        if "ratio" in r:  # end to end in a warm writer, against recognise() alone
            rows.append(
                Row(
                    f"speech -> DMP rollout, warm Writer, {r['backend']}, '{r['word']}' "
                    + ("(nothing heard)" if r["heard"] is None else f"(heard '{r['heard']}')"),
                    f"{r['total_ms']:.0f} ms",
                    "recognise() alone",
                    f"{r['recognise_ms']:.0f} ms",
                    r["ratio"],
                    f"<= {target_ratio}",
                )
            )
    return rows


def simulate_rows(d: dict) -> list[Row]:
    rows = []
    for r in d["rows"]:
        rows.append(
            Row(
                f"pen tracking error, {r['robot']}, '{r['word']}' (real-time factor "
                f"{r['realtime_factor']:.0f})",
                f"{1000 * r['tracking_mean_mm']:.1f} um",
                "plain PyBullet IK",
                f"{1000 * r['plain_tracking_mean_mm']:.1f} um",
                r["tracking_mean_mm"] / r["plain_tracking_mean_mm"],
            )
        )
    for robot in dict.fromkeys(r["robot"] for r in d["rows"]):
        r = max((r for r in d["rows"] if r["robot"] == robot), key=lambda r: r["letters"])
        rows.append(
            Row(
                f"IK error, {robot}, '{r['word']}'",
                f"{1000 * r['ik_error_mean_mm']:.2f} um",
                "null-space PyBullet IK alone",
                f"{1000 * r['null_space_ik_error_mean_mm']:,.0f} um",
                r["ik_error_mean_mm"] / r["null_space_ik_error_mean_mm"],
            )
        )
    return rows


def connections_rows(d: dict) -> list[Row]:
    rows = []
    reference = {r["decoding"]: r for r in d["rows"] if r["method"] == "alg1"}
    for r in d["rows"]:
        if r["method"] != "hand":
            continue
        ref = reference[r["decoding"]]
        rows.append(
            Row(
                f"connections cutting a letter's ink, {r['words']} words ({r['decoding']} letters)",
                f"{r['crossing']}/{r['connections']} ({r['crossing_share']:.0%})",
                "the paper's Algorithm 1",
                f"{ref['crossing']}/{ref['connections']} ({ref['crossing_share']:.0%})",
                max(r["crossing"], 0.5) / max(ref["crossing"], 0.5),
                "<= 10 %",
            )
        )
        bad, ref_bad = (x["looping"] + x["leaving_band"] for x in (r, ref))
        rows.append(
            Row(
                f"connections that loop + that swing past both letters ({r['decoding']} letters)",
                f"{r['looping']} + {r['leaving_band']} of {r['connections']}, "
                f"{r['pen_lifts']} pen lifts",
                "the paper's Algorithm 1",
                f"{ref['looping']} + {ref['leaving_band']} of {ref['connections']}, "
                f"{ref['pen_lifts']} pen lifts",
                max(bad, 0.5) / max(ref_bad, 0.5),
            )
        )
        rows.append(
            Row(
                f"compose a word (layout, connections, DMP), {r['decoding']} letters",
                f"{r['compose_ms_median']:.1f} ms",
                "the paper's Algorithm 1",
                f"{ref['compose_ms_median']:.1f} ms",
                r["compose_ms_median"] / ref["compose_ms_median"],
            )
        )
    return rows


def kinematics_rows(d: dict) -> list[Row]:
    table = d["table"]
    lasa, executed = table["LASA (human)"], table["human: executed"]
    paper = table["constant: executed"]
    noise = table["control: white noise"]
    targets = d["settings"]["targets"]
    names = {
        "beta": "speed-curvature power law beta",
        "speed_cv": "speed coefficient of variation",
        "lognormal_snr_db": "sigma-lognormal fit SNR (dB)",
    }
    rows = []
    for key, name in names.items():
        low, high = targets[key]
        rows.append(
            Row(
                f"{name}, executed pen tip, {len(d['settings']['words'])} words (the paper's "
                f"constant speed {paper[key]['median']:.2f}; white noise {noise[key]['median']:.2f})",
                f"{executed[key]['median']:.3f}",
                "LASA human demonstrations",
                f"{lasa[key]['median']:.3f}",
                executed[key]["median"] / lasa[key]["median"],
                f">= {low:g}" + (f", <= {high:g}" if high is not None else ""),
            )
        )
    return rows
