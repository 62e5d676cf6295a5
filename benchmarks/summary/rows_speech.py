"""Rows of the speech benchmarks: exact-word accuracy and latency of each back-end against the
reference back-end alone, per listening condition."""

from __future__ import annotations

import math

from .common import Row

# issue "Speech a robot can rely on": with a lexicon, this accuracy at no more than free
# transcription's median latency (latency ratio <= 1)
SPEECH_TARGETS = {
    ("whisper+rescore", "clean"): ">= 98%, latency <= 1x",
    ("whisper+rescore", "hard"): ">= 95%, latency <= 1x",
}


def speech_rows(d: dict) -> list[Row]:
    reference = d["settings"]["reference"]
    words = d["settings"]["words"]
    said = f"{len(words)} words: {', '.join(words[:3])}, ..."
    rows = []
    for condition, setting in d["settings"]["conditions"].items():
        ref = d["summary"][reference][condition]
        noise = "" if setting["snr_db"] is None else f", noise {setting['snr_db']:g} dB SNR"
        for name, summary in d["summary"].items():
            if name == reference:
                continue
            s = summary[condition]
            accuracy = f"{s['accuracy']:.1%}"
            if s.get("answered", 1) < 1:  # min_lead: asked again for the rest
                answered = s["accuracy_answered"] or 0.0
                accuracy += f", {answered:.1%} of the {s['answered']:.1%} answered"
            rows.append(
                Row(
                    f"speech, {condition} ({said}; {', '.join(setting['voices'])}{noise}), {name} "
                    "(exact word; median latency, latency ratio)",
                    f"{accuracy} ({s['median_ms']:,.0f} ms, {s['latency_ratio']:.2f}x)",
                    f"{reference} alone",
                    f"{ref['accuracy']:.1%} ({ref['median_ms']:,.0f} ms)",
                    s["accuracy"] / ref["accuracy"] if ref["accuracy"] else math.nan,
                    SPEECH_TARGETS.get((name, condition), ""),
                )
            )
    return rows
