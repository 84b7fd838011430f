"""The HTML kit of both reports (``realm eval report`` and ``realm sysid report|align``): one
stylesheet, the page skeleton, tables and embedded figures.

Pages are self-contained: CSS inline, figures as PNG data URIs. Cells that start with ``<`` are
inserted as HTML, everything else is escaped.
"""

from __future__ import annotations

import base64
import html
import io

CSS = """
body{font-family:system-ui,-apple-system,sans-serif;max-width:1240px;margin:1.5em auto;padding:0 1em;color:#222;line-height:1.35}
h1{font-size:1.55em;margin-bottom:.2em} h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0;font-size:.88em} td,th{border:1px solid #ddd;padding:3px 8px;text-align:right;vertical-align:top}
th{background:#f3f3f3} td.l,th.l{text-align:left} .bad{background:#fde2e2} .good{background:#e3f6e3}
.proto{display:grid;grid-template-columns:max-content 1fr;gap:2px 14px;font-size:.9em;background:#f7f7f9;border:1px solid #e2e2e8;
 padding:.6em .9em;border-radius:6px;margin:.6em 0}
.proto dt{color:#555} .proto dd{margin:0}
.headline{font-size:1.05em;margin:.6em 0} .headline b{font-size:1.15em}
.err{color:#a00;font-weight:600} .ok{color:#161} .warn{background:#fff3cd;border:1px solid #e6d28a;padding:.4em .7em;border-radius:4px}
.note{color:#555;font-size:.9em} img{max-width:100%}
.figs{display:flex;flex-wrap:wrap;gap:10px 28px;align-items:flex-start}
figure{margin:.6em 0;display:table} figure img{border:1px solid #eee}
figcaption{display:table-caption;caption-side:bottom;font-size:.86em;color:#444;padding-top:4px}
.vids{display:grid;grid-template-columns:repeat(auto-fill,minmax(380px,1fr));gap:12px}
.vid{border:1px solid #ddd;border-radius:6px;padding:6px;background:#fafafa;font-size:.85em}
.vid video{width:100%;height:auto;background:#000;display:block}
.tag{display:inline-block;padding:0 6px;border-radius:3px;font-weight:600}
.tag.s{background:#d8f0d8;color:#145214} .tag.f{background:#f8dcdc;color:#7a1010} .tag.e{background:#eee;color:#555}
.grid{display:flex;flex-wrap:wrap;gap:0 36px;align-items:flex-start} .grid h2{font-size:1.05em}
.cmp td.v{font-variant-numeric:tabular-nums} .cmp th[colspan]{text-align:center}
"""


def esc(s) -> str:
    return html.escape(str(s))


def table(header: list[str], rows: list[list], left: int = 1, cls: str = "",
          classes: list[list[str]] | None = None) -> str:
    """The first ``left`` columns are left-aligned; ``cls``: the table's class; ``classes``: a class
    per cell (``"bad"``/``"good"`` shade it), row by row."""
    def cell(v, i, tag, extra=""):
        names = " ".join(c for c in ("l" if i < left else "", extra) if c)
        attr = f' class="{names}"' if names else ""
        return f"<{tag}{attr}>{v if isinstance(v, str) and v.startswith('<') else esc(v)}</{tag}>"

    head = "<tr>" + "".join(cell(h, i, "th") for i, h in enumerate(header)) + "</tr>"
    body = "".join("<tr>" + "".join(cell(v, i, "td", classes[r][i] if classes else "") for i, v in enumerate(row)) + "</tr>"
                   for r, row in enumerate(rows))
    return f'<table class="{cls}">{head}{body}</table>'


def page(title: str, body: str) -> str:
    """A whole page: ``title`` in the browser tab, ``body`` as given."""
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{esc(title)}</title><style>{CSS}</style></head>"
            f"<body>{body}</body></html>")


def sections_page(title: str, sections: list[tuple[str, str]]) -> str:
    """A page of titled sections under a heading and a table of contents."""
    toc = "".join(f'<li><a href="#s{i}">{esc(t)}</a></li>' for i, (t, _) in enumerate(sections))
    body = "".join(f'<h2 id="s{i}">{esc(t)}</h2>{b}' for i, (t, b) in enumerate(sections))
    return page(title, f"<h1>{esc(title)}</h1><ul>{toc}</ul>{body}")


def png(fig, dpi: int = 100) -> bytes:
    """A matplotlib figure as PNG bytes (cropped to its content); the figure is closed."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def img(data: bytes, alt: str = "") -> str:
    """PNG bytes as an embedded image."""
    return f'<img src="data:image/png;base64,{base64.b64encode(data).decode()}" alt="{esc(alt)}">'


def figure(data: bytes, caption: str, alt: str) -> str:
    """PNG bytes as an embedded image with a caption (HTML) below it."""
    return f"<figure>{img(data, alt)}<figcaption>{caption}</figcaption></figure>"
