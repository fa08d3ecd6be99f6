"""The page of report.html without its content: the style, the few lines of vanilla JS that
sort and filter the verdict table and draw the figures with plotly.js (loaded from the file
`PLOTLY_JS` beside the page), and the Markdown our reports write as HTML."""
from __future__ import annotations

import html
import json
import re

PLOTLY_JS = "plotly.min.js"
_esc = html.escape

_INLINE = [(re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)"), r"<img alt='\1' src='\2'>"),
           (re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)"), r"<a href='\2'>\1</a>"),
           (re.compile(r"`([^`]+)`"), r"<code>\1</code>"),
           (re.compile(r"\*\*([^*]+)\*\*"), r"<b>\1</b>")]
_RAW = re.compile(r"^\s*</?(details|summary)\b.*>\s*$")


def _inline(text: str) -> str:
    out = _esc(text, quote=False)
    for pat, rep in _INLINE:
        out = pat.sub(rep, out)
    return out


def markdown_html(md: str) -> str:
    """The Markdown our reports write (headings, tables, lists, images, links, code blocks,
    <details>) as HTML; anything else a paragraph."""
    out, table, code, items = [], None, None, False
    for line in md.splitlines() + [""]:
        if code is not None:
            if line.startswith("```"):
                out.append("<pre>" + _esc("\n".join(code)) + "</pre>")
                code = None
            else:
                code.append(line)
            continue
        if table is not None and not line.startswith("|"):
            out.append(table + "</tbody></table></div>")
            table = None
        if items and not line.startswith("- "):
            out.append("</ul>")
            items = False
        if line.startswith("```"):
            code = []
        elif line.startswith("|"):
            cells = [c.strip().replace("\\|", "|")
                     for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]
            if table is None:
                table = ("<div class='scroll'><table class='md'><thead><tr>"
                         + "".join(f"<th>{_inline(c)}</th>" for c in cells)
                         + "</tr></thead><tbody>")
            elif not all(set(c) <= set("-: ") for c in cells):
                table += "<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in cells) + "</tr>"
        elif line.startswith("#"):
            level = min(len(line) - len(line.lstrip("#")) + 1, 6)
            out.append(f"<h{level}>{_inline(line.lstrip('#').strip())}</h{level}>")
        elif line.startswith("- "):
            if not items:
                out.append("<ul>")
                items = True
            out.append(f"<li>{_inline(line[2:])}</li>")
        elif _RAW.match(line):
            out.append(line.strip())
        elif line.strip():
            out.append(f"<p>{_inline(line)}</p>")
    return "\n".join(out)


_CSS = """body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1200px;
padding:0 1em;color:#222}h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.5em}
table{border-collapse:collapse;font-size:.85em}td,th{border:1px solid #ccc;padding:2px 6px;
text-align:left;vertical-align:top}#verdict-table th{cursor:pointer;background:#f3f3f3}
#verdict-table th.asc:after{content:" \\25B2"}#verdict-table th.desc:after{content:" \\25BC"}
table.facts th{background:#f3f3f3}.scroll{overflow-x:auto}
#verdict-table td{white-space:nowrap}#verdict-table td:last-child{white-space:normal}
.vscroll{max-height:480px;overflow:auto}#verdict-table thead th{position:sticky;top:0}
tr[data-verdict=agree] td:nth-last-child(2){color:#17692a}
tr[data-verdict=disagree] td:nth-last-child(2){color:#b00020;font-weight:bold}
.count{margin-right:.8em;padding:1px 6px;border-radius:3px;background:#eee}
.v-agree{background:#dff2e1}.v-disagree{background:#f8d7da}
.figs{display:grid;grid-template-columns:repeat(auto-fit,minmax(520px,1fr));gap:10px}
.xval-figure{min-height:320px;border:1px solid #eee}img{max-width:100%}
pre{background:#f6f6f6;padding:6px;overflow-x:auto}"""

_JS = """(function(){
const t=document.getElementById('verdict-table');
if(t){const body=t.tBodies[0],rows=Array.from(body.rows),
box=document.getElementById('verdict-filter'),
sel=document.getElementById('verdict-select'),shown=document.getElementById('verdict-shown');
function filter(){const q=box.value.toLowerCase(),v=sel.value;let n=0;
for(const r of rows){const on=(!v||r.dataset.verdict===v)&&r.textContent.toLowerCase().includes(q);
r.hidden=!on;if(on)n++;}shown.textContent=n;}
box.addEventListener('input',filter);sel.addEventListener('change',filter);
const key=s=>{const x=parseFloat(s.replace('\\u2212','-'));return isNaN(x)?null:x;};
for(const th of t.tHead.rows[0].cells){th.addEventListener('click',()=>{
const i=th.cellIndex,up=!th.classList.contains('asc');
for(const h of t.tHead.rows[0].cells)h.classList.remove('asc','desc');
th.classList.add(up?'asc':'desc');
rows.sort((a,b)=>{const p=a.cells[i].textContent,q=b.cells[i].textContent,x=key(p),y=key(q);
let c=(x!==null&&y!==null)?x-y:(x===null)-(y===null)||p.localeCompare(q);return up?c:-c;});
for(const r of rows)body.appendChild(r);});}}
const figs=JSON.parse(document.getElementById('xval-figures').textContent);
for(const f of figs){Plotly.newPlot(f.id,f.data,f.layout,{responsive:true,displaylogo:false});}
})();"""


def page(title: str, parts: list[str], figures: list[dict], tail: str = "") -> str:
    """The whole page: `parts` (HTML), the figures' divs and specs, then `tail`."""
    figs = [f for f in figures if f]
    divs = "".join(f"<div class='xval-figure' id='{_esc(f['id'])}'></div>" for f in figs)
    data = json.dumps(figs, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            f"<title>{_esc(title)}</title><style>{_CSS}</style>"
            f"<script src='{PLOTLY_JS}'></script></head><body>"
            + "\n".join(parts)
            + (f"<h2>Figures</h2><div class='figs'>{divs}</div>" if figs else "") + tail
            + f"<script type='application/json' id='xval-figures'>{data}</script>"
            + f"<script>{_JS}</script></body></html>\n")
