"""The report's tiny document model: blocks rendered to both Markdown and self-contained HTML."""

from __future__ import annotations

import base64
import html
import re
from dataclasses import dataclass, field

import pandas as pd


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
