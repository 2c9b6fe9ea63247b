"""Every report the lab writes, twice from one text: report.md to read in a terminal or a
repository, and a self-contained report.html beside it to open from a CI artifact or a mail.

The HTML is the Markdown converted (python3-markdown, its tables extension), so the two cannot
drift: same sections, same tables, same figures. What the page adds, with no network and no
library beyond a few lines of script in the page itself:
- every figure inside it (the PNG as a data URI), with an invisible hover target over each tagged
  point (hover.py) whose tooltip names the point's configuration;
- tables that sort when a header is clicked (numbers as numbers, '-' last) and, when long, a
  filter box;
- no external URL: nothing is fetched, so the page reads the same offline years later.
The Markdown is text, never HTML: what a report quotes (`auto:<engine>`, a program's error, a
file name) shows on the page as it reads in report.md instead of vanishing as an unknown tag.
"""
from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from analysis.common import hover

# Above this many rows a table gets a filter box: shorter ones are read at a glance.
FILTER_ROWS = 8

STYLE = """
body { font: 15px/1.5 system-ui, sans-serif; max-width: 72rem; margin: 1.5rem auto;
       padding: 0 1rem; color: #1d1d1f; }
h1, h2, h3 { line-height: 1.25; } h2 { border-bottom: 1px solid #ddd; padding-bottom: .2rem; }
code { background: #f3f3f3; padding: 0 .25rem; border-radius: 3px; font-size: 90%; }
pre { background: #f6f6f6; padding: .6rem; overflow-x: auto; }
table { border-collapse: collapse; margin: .6rem 0; font-size: 90%; display: block;
        overflow-x: auto; }
th, td { border: 1px solid #ddd; padding: .2rem .5rem; }
th { background: #f0f0f0; cursor: pointer; user-select: none; white-space: nowrap; }
th[aria-sort="ascending"]::after { content: " \\25B2"; }
th[aria-sort="descending"]::after { content: " \\25BC"; }
tbody tr:nth-child(even) { background: #fafafa; }
input.filter { margin: .4rem 0 0; padding: .2rem .4rem; width: 18rem; }
.plot { position: relative; display: inline-block; max-width: 100%; }
.plot img { display: block; max-width: 100%; height: auto; }
.pt { position: absolute; width: 14px; height: 14px; margin: -7px 0 0 -7px; border-radius: 50%; }
.pt:hover { outline: 2px solid #d33; }
#tip { position: absolute; display: none; background: #222; color: #fff; padding: .3rem .5rem;
       border-radius: 4px; font-size: 85%; max-width: 34rem; pointer-events: none; z-index: 9;
       white-space: pre-line; }
.missing { color: #b00; }
"""

SCRIPT = """
(function () {
  const tip = document.createElement("div");
  tip.id = "tip";
  document.body.appendChild(tip);
  function place(e) {
    tip.style.left = (e.pageX + 14) + "px";
    tip.style.top = (e.pageY + 14) + "px";
  }
  // The text follows the target under the pointer on every move, not only on entering it:
  // a scroll moves targets under a still pointer.
  function show(e) {
    tip.textContent = e.currentTarget.dataset.tip;
    tip.style.display = "block";
    place(e);
  }
  document.querySelectorAll(".pt").forEach(function (pt) {
    pt.addEventListener("mouseenter", show);
    pt.addEventListener("mousemove", show);
    pt.addEventListener("mouseleave", function () { tip.style.display = "none"; });
  });

  // A cell's sort key: its leading number ("1,234.5 M", "+5.1%", "0.12 s"), else its text;
  // "-" and empty cells are missing and go last in either order.
  function key(cell) {
    const text = cell.textContent.trim();
    if (text === "" || text === "-") return null;
    const m = text.replace(/,/g, "").match(/^[+-]?(\\d+\\.?\\d*|\\.\\d+)(e[+-]?\\d+)?/i);
    return m ? parseFloat(m[0]) : text.toLowerCase();
  }
  function compare(a, b) {
    if (typeof a === typeof b) return a < b ? -1 : a > b ? 1 : 0;
    return typeof a === "number" ? -1 : 1;  // numbers before words
  }
  function sort(table, th, column) {
    const order = th.getAttribute("aria-sort") === "ascending" ? "descending" : "ascending";
    table.querySelectorAll("th").forEach(function (h) { h.removeAttribute("aria-sort"); });
    th.setAttribute("aria-sort", order);
    const body = table.tBodies[0];
    const rows = Array.from(body.rows).map(function (row, i) {
      return { row: row, key: key(row.cells[column]), i: i };
    });
    rows.sort(function (x, y) {
      if (x.key === null || y.key === null) {
        return x.key === y.key ? x.i - y.i : x.key === null ? 1 : -1;
      }
      const c = compare(x.key, y.key);
      return (order === "ascending" ? c : -c) || x.i - y.i;
    });
    rows.forEach(function (r) { body.appendChild(r.row); });
  }
  document.querySelectorAll("table").forEach(function (table) {
    if (!table.tHead || !table.tBodies.length) return;
    Array.from(table.tHead.rows[0].cells).forEach(function (th, column) {
      th.title = "click to sort";
      th.addEventListener("click", function () { sort(table, th, column); });
    });
    if (table.tBodies[0].rows.length > FILTER_ROWS) {
      const box = document.createElement("input");
      box.type = "search";
      box.className = "filter";
      box.placeholder = "filter rows";
      box.addEventListener("input", function () {
        const needle = box.value.toLowerCase();
        Array.from(table.tBodies[0].rows).forEach(function (row) {
          row.style.display = row.textContent.toLowerCase().includes(needle) ? "" : "none";
        });
      });
      table.parentNode.insertBefore(box, table);
    }
  });
})();
""".replace("FILTER_ROWS", str(FILTER_ROWS))

IMAGE = re.compile(r"<img\b[^>]*>")
ATTRIBUTE = re.compile(r'(\w+)="([^"]*)"')


def write_pages(path: Path, text: str) -> Path:
    """Writes `text` to `path` (report.md) and its page to the same name with .html; returns the
    page. Runs of blank lines, left where an empty section joined its neighbours, become one."""
    text = re.sub(r"\n{3,}", "\n\n", text.strip()) + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    page = path.with_suffix(".html")
    page.write_text(to_html(text, path.parent))
    return page


def to_html(text: str, folder: Path) -> str:
    """The page of a Markdown text whose figures are PNG paths relative to `folder`."""
    import markdown  # imported here: only a report's writing needs it

    body = markdown.markdown(text, extensions=["tables", "fenced_code", "sane_lists",
                                               text_only()])
    body = IMAGE.sub(lambda m: figure(dict(ATTRIBUTE.findall(m.group(0))), folder), body)
    heading = re.search(r"^# (.+)$", text, re.MULTILINE)
    title = html.escape(heading.group(1) if heading else "report")
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{title}</title><style>{STYLE}</style></head>\n<body>\n{body}\n"
            f"<script>{SCRIPT}</script>\n</body></html>\n")


def text_only():
    """A Markdown extension that reads raw HTML and <autolinks> as the text they are: the
    reports are Markdown written for a terminal, where `<engine>` is a placeholder and `<a@b.c>`
    an address quoted from a program's output, not a tag or a link."""
    from markdown.extensions import Extension

    class TextOnly(Extension):
        def extendMarkdown(self, md):
            md.preprocessors.deregister("html_block")
            for pattern in ("html", "autolink", "automail"):
                md.inlinePatterns.deregister(pattern)

    return TextOnly()


def figure(attributes: dict, folder: Path) -> str:
    """A figure's PNG inline, with a hover target per tagged point; a visible note when the
    file is missing, never a broken image."""
    source = html.unescape(attributes.get("src", ""))
    alt = attributes.get("alt", "")
    png = folder / source
    if not source or not png.is_file():
        return f'<span class="missing">figure {html.escape(source)} is missing</span>'
    data = base64.b64encode(png.read_bytes()).decode("ascii")
    targets = "".join(
        f'<span class="pt" style="left:{100 * p["x"]:.3f}%;top:{100 * p["y"]:.3f}%" '
        f'data-tip="{html.escape(p["text"], quote=True)}"></span>'
        for p in hover.read_positions(png))
    return (f'<span class="plot"><img alt="{alt}" src="data:image/png;base64,{data}">'
            f'{targets}</span>')
