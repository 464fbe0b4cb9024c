"""Building blocks of rigopt's self-contained HTML reports: one inline style sheet, escaped text, tables,
and PNG figures embedded as data URIs, so a page opens offline."""

from __future__ import annotations

import base64
import html

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 2em auto;
       max-width: 1200px; padding: 0 1em; color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; }
th { background: #f2f2f2; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.good { color: #1a7f37; } td.bad { color: #b42318; }
.warning { background: #fff4e5; border: 1px solid #f0a030; padding: 0.6em 0.9em; border-radius: 4px; }
.note { color: #555; font-size: 0.9em; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { color: #555; font-size: 0.9em; }
"""


def escape(value) -> str:
    return html.escape(str(value), quote=True)


def pct(value) -> str:
    return "-" if value is None else f"{100.0 * value:.1f} %"


def num(value, digits: int = 2, unit: str = "") -> str:
    return "-" if value is None else f"{value:.{digits}f}{unit}"


def cell(text: str, cls: str = "") -> str:
    return f'<td class="{cls}">{text}</td>' if cls else f"<td>{text}</td>"


def table(header: list[str], rows: list[list[str]], numeric_from: int = 1) -> str:
    """An HTML table; ``rows`` hold already escaped cell HTML; columns from ``numeric_from`` are right-aligned
    unless a cell is given as a ready ``<td ...>`` element."""
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = []
    for row in rows:
        cells = [c if c.startswith("<td") else cell(c, "num" if k >= numeric_from else "") for k, c in enumerate(row)]
        body.append(f"<tr>{''.join(cells)}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def image(png: bytes, alt: str, caption: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{escape(alt)}">'
            f"<figcaption>{escape(caption)}</figcaption></figure>")


def page(title: str, body: list[str]) -> str:
    """A whole HTML document with the shared style; ``body`` holds ready HTML fragments."""
    head = ['<!DOCTYPE html>', '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{escape(title)}</title>", f"<style>{STYLE}</style></head><body>"]
    return "\n".join(head + body + ["</body></html>"]) + "\n"
