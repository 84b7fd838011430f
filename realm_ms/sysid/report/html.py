"""The page skeleton and small HTML helpers (no external assets: the page is self-contained)."""

from __future__ import annotations

import html

CSS = """
body{font-family:system-ui,sans-serif;max-width:1180px;margin:2em auto;color:#222}
h1{font-size:1.6em} h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em} td,th{border:1px solid #ddd;padding:3px 7px;text-align:right}
th{background:#f3f3f3} td.l,th.l{text-align:left} .bad{background:#fde2e2} .good{background:#e3f6e3}
.note{color:#555;font-size:.9em} img{max-width:100%}
"""


def esc(s) -> str:
    return html.escape(str(s))


def table(header: list[str], rows: list[list], left: int = 1, classes: list[list[str]] | None = None) -> str:
    out = ["<table><tr>" + "".join(f'<th class="{"l" if i < left else ""}">{esc(h)}</th>' for i, h in enumerate(header)) + "</tr>"]
    for r, row in enumerate(rows):
        cells = []
        for i, v in enumerate(row):
            cls = ("l " if i < left else "") + (classes[r][i] if classes else "")
            cells.append(f'<td class="{cls.strip()}">{v if isinstance(v, str) and v.startswith("<") else esc(v)}</td>')
        out.append("<tr>" + "".join(cells) + "</tr>")
    return "".join(out) + "</table>"


def page(title: str, sections: list[tuple[str, str]]) -> str:
    toc = "".join(f'<li><a href="#s{i}">{esc(t)}</a></li>' for i, (t, _) in enumerate(sections))
    body = "".join(f'<h2 id="s{i}">{esc(t)}</h2>{b}' for i, (t, b) in enumerate(sections))
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{esc(title)}</title><style>{CSS}</style></head>"
            f"<body><h1>{esc(title)}</h1><ul>{toc}</ul>{body}</body></html>")
