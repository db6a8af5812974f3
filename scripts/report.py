#!/usr/bin/env python3
"""Writes the fleet run report (index.html + summary.json) from what a demo or load-test run left
in its folder: the simulator's summary and replay viewer, the fleet manager's task database and
metrics. index.html is one self-contained file: the replay viewer travels inside it (gzip +
base64, unpacked by the browser), so it can be copied or mailed on its own; viewer.html stays
next to it for opening the viewer by itself. Usage: scripts/report.py RUN_DIR"""
import report_ledger
import base64
import gzip
import html
import json
import math
import os
import sqlite3
import sys

COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"]
MARKS = (("p50", 0.5, "#1f77b4"), ("p90", 0.9, "#ff7f0e"), ("p99", 0.99, "#d62728"))


def no_data(why, w=520, h=220):
    """A placeholder the size of a plot, saying why there is nothing to draw."""
    return (f'<div class="nodata" style="width:{w-2}px;height:{h-2}px">(no data: {html.escape(why)})</div>')


def nice_ticks(lo, hi, n=5, integer=False):
    """About n round tick values covering [lo, hi]."""
    span = hi - lo
    if span <= 0:
        return [lo]
    raw = span / n
    step = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 2.5, 5, 10):
        if raw <= step * m:
            step *= m
            break
    if integer:
        step = max(1, round(step))
    first = math.ceil(lo / step - 1e-9) * step
    return [round(first + i * step, 10) for i in range(int((hi - first) / step + 1e-9) + 1)]


def fmt(v):
    return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"


def svg_frame(w, h, x0, x1, y1, xlabel, ylabel, right=20, top=20, integer_y=False):
    """Axes with ticks, grid lines and labels for a plot of [x0, x1] × [0, y1]; returns the
    scales and the SVG of the frame. The plot area is x in [55, w-right], y in [top, h-40]."""
    left, bottom = 55, h - 40
    sx = lambda x: left + (x - x0) / ((x1 - x0) or 1) * (w - right - left)
    sy = lambda y: bottom - y / (y1 or 1) * (bottom - top)
    parts = []
    for t in nice_ticks(0, y1, 4, integer_y):
        parts.append(f'<line x1="{left}" y1="{sy(t):.1f}" x2="{w-right}" y2="{sy(t):.1f}" stroke="#e4e4e4"/>'
                     f'<text x="{left-4}" y="{sy(t)+4:.1f}" text-anchor="end">{fmt(t)}</text>')
    for t in nice_ticks(x0, x1, 6):
        parts.append(f'<line x1="{sx(t):.1f}" y1="{bottom}" x2="{sx(t):.1f}" y2="{bottom+4}" stroke="#444"/>'
                     f'<text x="{sx(t):.1f}" y="{bottom+15}" text-anchor="middle">{fmt(t)}</text>')
    parts.append(f'<line x1="{left}" y1="{bottom}" x2="{w-right}" y2="{bottom}" stroke="#444"/>'
                 f'<line x1="{left}" y1="{top}" x2="{left}" y2="{bottom}" stroke="#444"/>'
                 f'<text x="{(left + w - right)/2}" y="{h-6}" text-anchor="middle">{html.escape(xlabel)}</text>'
                 f'<text x="13" y="{(top + bottom)/2}" transform="rotate(-90 13 {(top + bottom)/2})" '
                 f'text-anchor="middle">{html.escape(ylabel)}</text>')
    return sx, sy, "".join(parts)


def svg_open(w, h):
    return f'<svg width="{w}" height="{h}" xmlns="http://www.w3.org/2000/svg" font-size="11" font-family="sans-serif">'


def svg_lines(series, w=520, h=240, xlabel="", ylabel="", why="nothing recorded", legend_title=""):
    """Several named lines [(name, [(x, y)...])] on shared axes, with a legend right of the plot."""
    series = [(n, pts) for n, pts in series if pts]
    if not series:
        return no_data(why, w, h)
    xs = [x for _, pts in series for x, _ in pts]
    x0, x1 = min(xs), max(xs)
    y1 = max(y for _, pts in series for _, y in pts) or 1
    sx, sy, frame = svg_frame(w, h, x0, x1, y1, xlabel, ylabel, right=95)
    paths, legend = [], []
    if legend_title:
        legend.append(f'<text x="{w-85}" y="24" font-weight="bold">{html.escape(legend_title)}</text>')
    for i, (name, pts) in enumerate(series):
        c = COLORS[i % len(COLORS)]
        d = " ".join(f"{'M' if k == 0 else 'L'}{sx(x):.1f},{sy(y):.1f}" for k, (x, y) in enumerate(pts))
        paths.append(f'<path d="{d}" fill="none" stroke="{c}" stroke-width="1.5"/>')
        y = 24 + (i + (1 if legend_title else 0)) * 14
        legend.append(f'<line x1="{w-85}" y1="{y-4}" x2="{w-71}" y2="{y-4}" stroke="{c}" stroke-width="2"/>'
                      f'<text x="{w-67}" y="{y}">{html.escape(name)}</text>')
    return f'{svg_open(w, h)}{frame}{"".join(paths)}{"".join(legend)}</svg>'


def svg_error(runs, hidden, key, scale=1.0, w=640, h=260, ylabel="", why="no localization samples"):
    """Error over time of one or more runs [(label, series)], the mean over robots solid and the
    worst robot dashed, with the stretches in which landmarks were hidden shaded."""
    runs = [(name, s) for name, s in runs if s]
    if not runs:
        return no_data(why, w, h)
    x1 = max(p["t"] for _, s in runs for p in s)
    y1 = max(p[key + "_max"] * scale for _, s in runs for p in s) or 1
    sx, sy, frame = svg_frame(w, h, 0, x1, y1, "simulated time (s)", ylabel, right=150)
    shade = "".join(f'<rect x="{sx(a):.1f}" y="20" width="{max(0.0, sx(min(b, x1)) - sx(a)):.1f}" height="{h-60}" '
                    f'fill="#f3e7c9"/>' for a, b in hidden if a < x1)
    paths, legend = [], [f'<rect x="{w-142}" y="12" width="12" height="10" fill="#f3e7c9"/>'
                         f'<text x="{w-126}" y="21">landmarks hidden</text>']
    for i, (name, s) in enumerate(runs):
        c = COLORS[i % len(COLORS)]
        for j, (stat, dash) in enumerate((("mean", ""), ("max", ' stroke-dasharray="4 3"'))):
            d = " ".join(f'{"M" if k == 0 else "L"}{sx(p["t"]):.1f},{sy(p[key + "_" + stat] * scale):.1f}'
                         for k, p in enumerate(s))
            paths.append(f'<path d="{d}" fill="none" stroke="{c}" stroke-width="{1.8 if not dash else 1}"{dash}/>')
            y = 40 + (2 * i + j) * 16
            legend.append(f'<line x1="{w-142}" y1="{y-4}" x2="{w-130}" y2="{y-4}" stroke="{c}" stroke-width="2"{dash}/>'
                          f'<text x="{w-126}" y="{y}">{html.escape(name)} {"mean" if not j else "worst robot"}</text>')
    return f'{svg_open(w, h)}{shade}{frame}{"".join(paths)}{"".join(legend)}</svg>'


def localization_html(run, lt):
    """Each robot's own pose estimate against the truth (fleet-sim --localization) and what the
    localizers did with their scan lines (the agents' metrics)."""
    path = os.path.join(run, "localization.json")
    if not os.path.exists(path):
        return ""
    loc = json.load(open(path))
    hidden = sorted(tuple(h) for h in loc.get("hidden", []))
    rows = ""
    for key, label in (("overall", "whole run"), ("hidden_stretches", "landmarks hidden"), ("visible_stretches", "landmarks visible")):
        st = loc.get(key, {})
        if st.get("samples"):
            rows += (f"<tr><td>{label}</td><td>{st['samples']}</td><td>{st['pos_rmse']*100:.2f}</td><td>{st['pos_p95']*100:.2f}</td>"
                     f"<td>{st['pos_max']*100:.2f}</td><td>{math.degrees(st['head_rmse']):.2f}</td><td>{math.degrees(st['head_max']):.2f}</td></tr>")
    lines = {}
    for a in (lt or {}).get("agents", []):
        for k, v in a.get("localization", {}).items():
            lines[k] = (lines.get(k, 0) + v) if not isinstance(v, bool) else v
    counts = "".join(f"<tr><td>{html.escape(k)}</td><td>{v}</td></tr>" for k, v in lines.items())
    series = loc.get("series", [])
    return f"""<h2 id="localization">Localization error</h2>
<p class="note" style="max-width:900px">Each robot's published pose estimate against the simulator's truth of the same instant
(lockstep stamps), per second: the mean over robots and the worst robot. Line updates:
{'on' if lines.get('line_updates', True) else '<b>off</b>'}{'; landmarks hidden ' + ', '.join(f'{a:g}–{b:g} s' for a, b in hidden) if hidden else ''}.</p>
<div class="grid"><div><h3>Position error</h3>{svg_error([('run', series)], hidden, 'pos', 100, ylabel='position error (cm)')}</div>
<div><h3>Heading error</h3>{svg_error([('run', series)], hidden, 'head', 180 / math.pi, ylabel='|heading error| (°)')}</div></div>
<div class="grid"><div><table><tr><th>samples</th><th>n</th><th>pos RMSE (cm)</th><th>pos p95 (cm)</th><th>pos max (cm)</th><th>heading RMSE (°)</th><th>heading max (°)</th></tr>{rows}</table></div>
<div><table><tr><th>scan lines (all agents)</th><th>count</th></tr>{counts}</table></div></div>"""


def svg_line(points, w=520, h=240, xlabel="", ylabel="", why="nothing recorded", diagonal=None):
    """One line; diagonal=(label) also draws y = x, dashed, for reference."""
    if not points:
        return no_data(why, w, h)
    xs = [p[0] for p in points]
    x0, x1 = min(xs), max(xs)
    y1 = max(p[1] for p in points) or 1
    sx, sy, frame = svg_frame(w, h, x0, x1, y1, xlabel, ylabel)
    path = " ".join(f"{'M' if i == 0 else 'L'}{sx(x):.1f},{sy(y):.1f}" for i, (x, y) in enumerate(points))
    ref = ""
    if diagonal:
        e = min(x1, y1)
        ref = (f'<path d="M{sx(max(x0, 0)):.1f},{sy(max(x0, 0)):.1f} L{sx(e):.1f},{sy(e):.1f}" stroke="#999" '
               f'stroke-dasharray="4 3" fill="none"/><text x="{sx(e)-4:.1f}" y="{sy(e)+14:.1f}" '
               f'text-anchor="end" fill="#777">{html.escape(diagonal)}</text>')
    return (f'{svg_open(w, h)}{frame}{ref}<path d="{path}" fill="none" stroke="#1f77b4" stroke-width="2"/></svg>')


def svg_hist(values, bins=20, w=520, h=240, xlabel="", ylabel="tasks", why="no samples", color="#2ca02c"):
    """A histogram of values from 0 (times), with dashed p50 / p90 / p99 markers and their values
    above the plot."""
    if not values:
        return no_data(why, w, h)
    lo, hi = 0.0, max(values)
    nt = nice_ticks(0, hi, 6)
    if len(nt) < 2:  # all zero
        hi = 1.0
    elif nt[-1] < hi:  # bins on round edges: up to the first tick at or above the maximum
        hi = nt[-1] + (nt[1] - nt[0])
    width = (hi - lo) / bins
    counts = [0] * bins
    for v in values:
        counts[min(bins - 1, int((v - lo) / width))] += 1
    top = max(counts)
    sx, sy, frame = svg_frame(w, h, lo, hi, top, xlabel, ylabel, top=30, integer_y=True)
    bars = "".join(
        f'<rect x="{sx(lo + i*width)+0.5:.1f}" y="{sy(c):.1f}" width="{max(sx(lo + width) - sx(lo) - 1, 0.5):.1f}" '
        f'height="{sy(0) - sy(c):.1f}" fill="{color}" fill-opacity="0.75"><title>{fmt(lo + i*width)}–'
        f'{fmt(lo + (i+1)*width)}: {c}</title></rect>'
        for i, c in enumerate(counts) if c)
    marks, x = [], 55
    for name, q, c in MARKS:
        v = pct(values, q)
        marks.append(f'<line x1="{sx(v):.1f}" y1="30" x2="{sx(v):.1f}" y2="{h-40}" stroke="{c}" stroke-dasharray="4 3"/>')
        label = f"{name} {v:.4g}"
        marks.append(f'<line x1="{x}" y1="11" x2="{x+14}" y2="11" stroke="{c}" stroke-dasharray="4 3"/>'
                     f'<text x="{x+18}" y="15" fill="{c}">{html.escape(label)}</text>')
        x += 30 + 6.5 * len(label)
    marks.append(f'<text x="{w-20}" y="15" text-anchor="end" fill="#555">n = {len(values)}</text>')
    return f'{svg_open(w, h)}{frame}{bars}{"".join(marks)}</svg>'


def pct(values, q):
    if not values:
        return None
    v = sorted(values)  # nearest rank, as fleetctl's task ledger
    return v[min(len(v), max(1, math.ceil(q * len(v)))) - 1]


def percentiles(values):
    return {"p50": pct(values, 0.5), "p90": pct(values, 0.9), "p99": pct(values, 0.99),
            "max": pct(values, 1.0), "count": len(values)}


def replay_header(run):
    path = os.path.join(run, "replay.jsonl.gz")
    if not os.path.exists(path):
        return {}
    with gzip.open(path, "rt") as f:
        for line in f:
            d = json.loads(line)
            return d if d.get("type") == "header" else {}
    return {}


def risk_levels_over_time(run):
    """Area (m²) of the risk map at or above each iso-level, per recorded map in the replay. Level l
    of K holds collision probabilities in ((l-1)/K, l/K], so "at or above l" is p > (l-1)/K."""
    path = os.path.join(run, "replay.jsonl.gz")
    if not os.path.exists(path):
        return []
    levels = {}
    K = 0
    with gzip.open(path, "rt") as f:
        for line in f:
            if '"risk"' not in line:
                continue
            d = json.loads(line)
            r = d.get("risk")
            if not r or "runs" not in r:
                continue
            cell = r.get("resolution", 0.1) ** 2
            K = r.get("levels", 10)
            counts = [0] * (K + 1)
            for level, n in r["runs"]:
                if 0 <= level < len(counts):
                    counts[level] += n
            for l in range(1, len(counts)):
                levels.setdefault(l, []).append((d.get("t", 0.0), sum(counts[l:]) * cell))
    shown = {1, 2, 3, 5, 7, 9, K} if K == 10 else set(sorted(levels)[::max(1, K // 6)]) | {K}
    return [(f"p > {(l - 1) / K:.2g}", pts) for l, pts in sorted(levels.items()) if l in shown]


def traffic_over_time(run):
    """From the replay's traffic layer (reserved traffic): per simulated second, robots standing on a
    station's queue place (within 0.3 m of a queue node), robots whose release lets them drive (a
    base beyond the node they are at) and robots held at their node; and each roadmap revision
    (closures) with its time and closed nodes. None when the replay has no roadmap."""
    path = os.path.join(run, "replay.jsonl.gz")
    if not os.path.exists(path):
        return None
    header = {}
    queue_cells = {}  # (ix, iy) of 0.5 m cells -> queue node positions
    releases = {}
    waiting, driving, held, revisions = [], [], [], []
    last_t = -1.0
    with gzip.open(path, "rt") as f:
        for line in f:
            d = json.loads(line)
            if d.get("type") == "header":
                header = d
                continue
            rm = d.get("roadmap")
            if rm:
                n = rm["nodes"]
                queue_cells = {}
                for v, k in enumerate(rm["kinds"]):
                    if k == 3:
                        x, y = n[2 * v], n[2 * v + 1]
                        queue_cells.setdefault((int(x // 0.5), int(y // 0.5)), []).append((x, y))
                revisions.append((d.get("t", 0.0), rm.get("revision", 0), len(rm.get("closed", []))))
            if d.get("releases_reset"):
                releases = {}  # a new traffic manager: the earlier releases no longer hold
            for rid, rel in (d.get("releases") or {}).items():
                releases[rid] = rel
            t = d.get("t", 0.0)
            if not revisions or t - last_t < 1.0:
                continue
            last_t = t
            ids = [r.get("id") for r in header.get("robots", [])]
            q = 0
            for r in d.get("robots", []):
                cx, cy = int(r[0] // 0.5), int(r[1] // 0.5)
                near = any((r[0] - x) ** 2 + (r[1] - y) ** 2 <= 0.09
                           for dx in (-1, 0, 1) for dy in (-1, 0, 1)
                           for (x, y) in queue_cells.get((cx + dx, cy + dy), ()))
                q += 1 if near else 0
            may = sum(1 for i in ids if i in releases and len(releases[i]["b"]) > 1)
            stay = sum(1 for i in ids if i in releases and len(releases[i]["b"]) <= 1)
            waiting.append((t, q))
            driving.append((t, may))
            held.append((t, stay))
    if not revisions:
        return None
    return {"series": [("may drive", driving), ("held", held), ("in a queue", waiting)], "revisions": revisions}


def traffic_html(run):
    t = traffic_over_time(run)
    if t is None:
        return ""
    rows = "".join(f'<tr><td class="r">{tt:.1f}</td><td class="r">{rev}</td><td class="r">{closed}</td></tr>'
                   for tt, rev, closed in t["revisions"])
    return f"""<h2 id="traffic">Traffic layer</h2>
<div class="grid"><div>{svg_lines(t['series'], w=640, h=260, xlabel='simulated time (s)', ylabel='robots', legend_title='robots', why='no releases in the replay')}</div>
<div><h3>Roadmap revisions (closures)</h3><table><tr><th>at (s)</th><th>revision</th><th>closed nodes</th></tr>{rows}</table>
<p class="note">From the traffic manager's Roadmap and TrafficRelease topics as the simulator recorded them: robots whose
release lets them drive on ("may drive": a base beyond their node), robots held at their node ("held": waiting on a
dependency, on their goal, docked or idle), and robots standing on a station's queue place ("in a queue"). The replay below draws the roadmap (queue places purple,
closed nodes red) and each robot's base (solid) and horizon (dashed).</p></div></div>
"""


def embedded_viewer(run):
    """The replay viewer as an iframe whose document travels inside this page (gzip + base64):
    a few lines of script unpack it into srcdoc, so the page needs no other file."""
    path = os.path.join(run, "viewer.html")
    if not os.path.exists(path):
        return no_data("the run left no viewer.html", 600, 80)
    raw = open(path, "rb").read()
    packed = base64.b64encode(gzip.compress(raw, 9, mtime=0)).decode("ascii")
    return f"""<iframe id="viewer" title="replay viewer"></iframe>
<p id="viewer-note" class="note"></p>
<script id="viewer-gz" type="application/octet-stream">{packed}</script>
<script>
(async () => {{
  const note = document.getElementById("viewer-note");
  try {{
    const b = atob(document.getElementById("viewer-gz").textContent.trim());
    const bytes = Uint8Array.from(b, c => c.charCodeAt(0));
    if (!window.DecompressionStream) throw new Error("this browser has no DecompressionStream");
    const text = await new Response(new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"))).text();
    document.getElementById("viewer").srcdoc = text;
  }} catch (e) {{
    note.textContent = "The embedded viewer could not be unpacked (" + e.message + "); open viewer.html from the run folder instead.";
  }}
}})();
</script>
<noscript><p>The embedded replay viewer needs JavaScript.</p></noscript>"""


def num(v, spec=".2f"):
    return "—" if v is None else format(v, spec)


def latency_table(blocks):
    """[(name, what, {p50, p90, p99, max, count})] as one table, seconds of simulated time."""
    head = "<tr><th></th><th>from → to</th><th>p50</th><th>p90</th><th>p99</th><th>max</th><th>n</th></tr>"
    body = "".join(f"<tr><td>{html.escape(n)}</td><td>{html.escape(what)}</td>"
                   + "".join(f'<td class="r">{num(p.get(q))}</td>' for q in ("p50", "p90", "p99", "max"))
                   + f'<td class="r">{p.get("count", 0)}</td></tr>' for n, what, p in blocks)
    return f"<table>{head}{body}</table>"


def bound_html(b):
    """The fleet against the kinematic bound (fleetctl loadtest's kinematic_bound block)."""
    if not b:
        return ""
    if "error" in b:
        return f"<h3>Against the kinematic bound</h3><p>not computed: {html.escape(str(b['error']))}</p>"
    cruise = ", ".join(f"{c:g}" for c in b.get("cruise_m_s", []))
    rows = [("tasks done with a bound", f"{b.get('tasks', 0)} of {b.get('tasks_done', 0)}"),
            ("mean task time (last assignment → done)", f"{num(b.get('mean_task_time_s'), '.1f')} s"),
            ("mean kinematic bound", f"{num(b.get('mean_bound_s'), '.1f')} s"),
            ("task time ÷ bound", f"<b>{num(b.get('task_time_over_bound'))}×</b>")]
    table = "".join(f"<tr><td>{html.escape(k)}</td><td class=\"r\">{v}</td></tr>" for k, v in rows)
    unbounded = "".join(f"<li>{html.escape(str(u.get('id')))}: {html.escape(str(u.get('reason')))}</li>"
                        for u in b.get("unbounded", []))
    ratios = [t["ratio"] for t in b.get("per_task", []) if t.get("ratio") is not None]
    return f"""<h3>Against the kinematic bound</h3><div class="grid"><div><table>{table}</table>
<p class="note">The bound of a task: the shortest way for the robot's disc on the free map (not the roadmap) from where it
was when the task was last assigned to the pickup and on to the drop-off, at the agent's cruise ({html.escape(cruise)} m/s),
plus the load and unload dwell. A ratio of 1 is a robot that never slows, turns or waits.</p>
{f'<p>Without a bound:</p><ul>{unbounded}</ul>' if unbounded else ''}</div>
<div>{svg_hist(ratios, xlabel='task time ÷ its bound', why='no task with a bound', color='#8c564b')}</div></div>"""


def waiting_series(db):
    """Tasks waiting (stored, not assigned) over simulated time, as fleetctl's saturated window counts
    them: the count after the last transition of each stamp."""
    queued, waiting, out = {}, 0, []
    rows = db.execute("select task_id, to_state, stamp_ns from transitions order by seq").fetchall()
    for i, (task, to, stamp) in enumerate(rows):
        now = to == "queued"
        waiting += (1 if now and not queued.get(task) else -1 if queued.get(task) and not now else 0)
        queued[task] = now
        if i + 1 == len(rows) or rows[i + 1][2] != stamp:
            out.append((stamp / 1e9, waiting))
    return out


def saturated_html(s, waiting, done_at, end_s, w=640, h=260):
    """fleetctl's saturated window: tasks waiting against the robot count, the window shaded, and
    the tasks done over time."""
    if not s:
        return ""
    robots = s.get("robots", 0)
    if s.get("found"):
        rows = [("window (at least as many tasks waiting as robots)",
                 f"{s['from_s']:.0f}–{s['to_s']:.0f} s (held {100 * s.get('held_fraction', 0):.0f} % of it)"),
                ("tasks done in it", f"{s['done']}"),
                ("the fleet's rate in it", f"{s['fleet_rate_per_h']:.1f} tasks/h, <b>{s['per_robot_rate_per_h']:.2f}</b> per robot")]
        table = "<table>" + "".join(f"<tr><td>{html.escape(k)}</td><td class=\"r\">{v}</td></tr>" for k, v in rows) + "</table>"
    else:
        table = f"<p>No saturated window: {html.escape(str(s.get('why', '')))} (peak {s.get('peak_waiting', 0)} waiting, {robots} robots).</p>"
    if not waiting:
        return f"<h3>Saturated window</h3>{table}"
    pts = [(0.0, 0)]
    for t, n in waiting:
        pts += [(t, pts[-1][1]), (t, n)]
    pts.append((end_s, pts[-1][1]))
    done = [(0.0, 0)] + [(t, i + 1) for i, t in enumerate(sorted(done_at))] + [(end_s, len(done_at))]
    y1 = max(max(n for _, n in pts), len(done_at), robots) or 1
    sx, sy, frame = svg_frame(w, h, 0.0, end_s or 1.0, y1, "simulated time (s)", "tasks", right=150, integer_y=True)
    shade = (f'<rect x="{sx(s["from_s"]):.1f}" y="20" width="{max(0.0, sx(s["to_s"]) - sx(s["from_s"])):.1f}" '
             f'height="{h-60}" fill="#e3eefa"/>' if s.get("found") else "")
    line = lambda p, c, dash="": (f'<path d="{" ".join(("M" if k == 0 else "L") + f"{sx(x):.1f},{sy(y):.1f}" for k, (x, y) in enumerate(p))}" '
                                  f'fill="none" stroke="{c}" stroke-width="1.6"{dash}/>')
    legend = (f'<rect x="{w-142}" y="12" width="12" height="10" fill="#e3eefa"/><text x="{w-126}" y="21">saturated window</text>'
              f'<line x1="{w-142}" y1="33" x2="{w-128}" y2="33" stroke="#1f77b4" stroke-width="2"/><text x="{w-124}" y="37">tasks waiting</text>'
              f'<line x1="{w-142}" y1="49" x2="{w-128}" y2="49" stroke="#d62728" stroke-dasharray="4 3" stroke-width="2"/><text x="{w-124}" y="53">robots ({robots})</text>'
              f'<line x1="{w-142}" y1="65" x2="{w-128}" y2="65" stroke="#2ca02c" stroke-width="2"/><text x="{w-124}" y="69">tasks done</text>')
    dashed = ' stroke-dasharray="4 3"'
    svg = (f'{svg_open(w, h)}{shade}{frame}{line(pts, "#1f77b4")}'
           f'{line([(0.0, robots), (end_s, robots)], "#d62728", dashed)}'
           f'{line(done, "#2ca02c")}{legend}</svg>')
    return f"""<h3>Saturated window</h3><div class="grid"><div>{table}
<p class="note">The per-robot efficiency is taken while at least as many tasks wait as there are robots: every robot that
finishes can chain the next task, so the rate there is the fleet's capacity, without the ramp-up from parking or the tail
after the last task was posted.</p></div><div>{svg}</div></div>"""


def loadtest_html(lt, saturated=""):
    if not lt:
        return ""
    a = lt.get("accounting", {})
    bad = (a.get("lost", 0) or 0) + (a.get("duplicated", 0) or 0)
    verdict = (f'<p style="font-size:1.3em;color:{"#b00" if bad else "#070"}"><b>{a.get("lost")} lost, '
               f'{a.get("duplicated")} duplicated</b> of {a.get("acknowledged")} acknowledged tasks</p>')
    cell = lambda v: f"{v:.1f}" if isinstance(v, float) else html.escape(json.dumps(v))
    rows = lambda d: "".join(f"<tr><td>{html.escape(str(k).replace('_', ' '))}</td><td class=\"r\">{cell(v)}</td></tr>"
                             for k, v in d.items())
    acc = {k: a.get(k) for k in ("acknowledged", "done", "failed", "cancelled", "still_tracked", "lost",
                                 "duplicated", "known_not_acknowledged", "unstamped")}
    faults = "".join(f"<tr><td class=\"r\">{e.get('sim_s', 0):.1f}</td><td>{html.escape(e.get('event', ''))}</td></tr>"
                     for e in lt.get("faults", []))
    faults = (f"<table><tr><th>simulated s</th><th>event</th></tr>{faults}</table>" if faults
              else "<p>none</p>")
    # --store postgresql: two managers on a database of the run's own; each kill of the active one timed.
    store = lt.get("store", {})
    takeover = store.get("takeover_s", {})
    store_html = (f"<p>Task store PostgreSQL, {store.get('managers', 2)} managers: {takeover.get('count', 0)} "
                  f"takeover(s) after a kill of the active one, p50 {takeover.get('p50', 0):.2f} s, "
                  f"max {takeover.get('max', 0):.2f} s; {store.get('takeovers_failed', 0)} not within 30 s.</p>"
                  if store.get("backend") == "postgresql" else "")
    progress = [(p["wall_s"], p["sim_s"]) for p in lt.get("progress", [])]
    # The robot agent processes: the control rate they achieved and how their robots dealt with
    # each other (agent-K_metrics.json, collected by fleetctl loadtest).
    agent_rows = "".join(
        f"<tr><td>{html.escape(str(m.get('id', '?')))}</td><td class=\"r\">{m.get('robots', 0)}</td>"
        f"<td class=\"r\">{m.get('achieved_hz', 0):.2f} / {m.get('configured_hz', 0):.0f}</td><td class=\"r\">{m.get('overruns', 0)}</td>"
        f"<td class=\"r\">{m.get('cycle_ms', {}).get('p50', 0):.2f} / {m.get('cycle_ms', {}).get('p99', 0):.2f}</td>"
        f"<td class=\"r\">{m.get('conduct', {}).get('standoffs', 0)} / {m.get('conduct', {}).get('wait_cycles', 0)} / "
        f"{m.get('conduct', {}).get('backoffs', 0)} / {m.get('conduct', {}).get('returns', 0)} / "
        f"{m.get('conduct', {}).get('detours', 0)}</td></tr>"
        for m in lt.get("agents", []))
    agents = (f"<h3>Robot agents ({html.escape(str(lt.get('clock', 'lockstep')))} clock)</h3><table>"
              "<tr><th>process</th><th>robots</th><th>cycles/s (achieved / configured)</th><th>overruns</th>"
              "<th>cycle ms p50 / p99</th><th>standoffs / wait cycles / back-offs / returns / detours</th></tr>"
              f"{agent_rows}</table>") if agent_rows else ""
    lat = latency_table([("assignment", "submitted → first assigned", a.get("assignment_latency_s", {})),
                         ("end to end", "submitted → done", a.get("end_to_end_latency_s", {}))])
    bound = (report_ledger.fleet_bound_html(lt.get("fleet_bound")) + bound_html(lt.get("kinematic_bound"))
             + report_ledger.robot_time_html(lt.get("robot_time")) + report_ledger.stations_html(lt.get("stations")))
    return f"""<h2 id="loadtest">Load test</h2>{verdict}
<p>{lt.get('robots')} robots in {lt.get('agent_processes')} agent process(es), {lt.get('humans')} humans,
{lt.get('sim_time_s', 0):.0f} s simulated in {lt.get('wall_time_s', 0):.0f} s wall
(<b>{lt.get('real_time_factor', 0):.2f}×</b> real time){' — stopped by the wall-time limit' if lt.get('wall_limited') else ''}.
Arrival rate {lt.get('rate_per_min', 0):g} tasks per simulated minute. Fault plan: {html.escape(', '.join(lt.get('fault_plan', [])) or 'none')}.</p>
<div class="grid"><div><h3>Acknowledged tasks (fleetctl's ledger)</h3><table>{rows(acc)}</table>
<h3>Throughput</h3><table>{rows(lt.get('throughput', {}))}</table></div>
<div><h3>Latency of acknowledged tasks (s, simulated)</h3>{lat}
<h3>Faults injected</h3>{faults}{store_html}</div>
<div><h3>Simulated vs wall time</h3>{svg_line(progress, xlabel='wall time (s)', ylabel='simulated time (s)', why='no progress samples', diagonal='1× real time')}</div></div>
{bound}
{saturated}
{agents}"""


def main(run):
    sim = json.load(open(os.path.join(run, "sim_summary.json")))
    metrics_path = os.path.join(run, "manager_metrics_final.json")
    manager = json.load(open(metrics_path)) if os.path.exists(metrics_path) else {}
    db = sqlite3.connect(os.path.join(run, "fleet.db"))
    states = dict(db.execute("select state, count(*) from tasks group by state").fetchall())
    created = {}
    first_assigned = {}
    finished = set()
    unstamped = set()
    latest = 0
    done_at = []
    durations = []  # submitted → done: end to end
    executions = []  # first assigned → done
    assign_lat = []  # submitted → first assigned
    for task, to, stamp in db.execute("select task_id, to_state, stamp_ns from transitions order by seq"):
        if task not in created:
            created[task] = stamp
            # A restarted manager stamps tasks it stores before its first Clock with 0 (see
            # fleetctl's task ledger): no latency samples from those.
            if stamp + 1e9 < latest:
                unstamped.add(task)
        latest = max(latest, stamp)
        if to == "done" and task not in finished:  # a task's first "done" only, as the ledger
            finished.add(task)
            done_at.append(stamp / 1e9)
            if task not in unstamped:
                durations.append((stamp - created[task]) / 1e9)
                if task in first_assigned:
                    executions.append((stamp - first_assigned[task]) / 1e9)
        if to == "assigned" and task not in first_assigned:
            first_assigned[task] = stamp
            if task not in unstamped:
                assign_lat.append((stamp - created[task]) / 1e9)
    sim_s = sim.get("sim_time_s", 0) or 1
    done = len(done_at)
    cumulative = [(0.0, 0)]
    for i, t in enumerate(sorted(done_at)):  # a step up at each completion
        cumulative += [(t, i), (t, i + 1)]
    cumulative.append((sim_s, done))
    header = replay_header(run)
    near_m = header.get("near_miss_m")
    scenario_path = os.path.join(run, "scenario.json")
    if near_m is None and os.path.exists(scenario_path):
        near_m = json.load(open(scenario_path)).get("near_miss_m")
    end_to_end = percentiles(durations)
    summary = {
        "scenario": sim.get("scenario"),
        "sim_time_s": sim_s,
        "robots": sim.get("robots"),
        "humans": sim.get("humans"),
        "tasks": {"submitted": sum(states.values()), "by_state": states, "done": done,
                  "per_hour": done * 3600.0 / sim_s,
                  # Task time is end to end (submitted → done), as end_to_end_latency_s below.
                  "time_s": end_to_end,
                  "execution_time_s": percentiles(executions)},
        "assignment_latency_s": percentiles(assign_lat),
        "end_to_end_latency_s": end_to_end,
        "manager_assignment_latency_ms": manager.get("assign_latency_ms"),
        "requeued": manager.get("requeued"),
        "safety": {"contacts": sim.get("contacts"), "min_separation_m": sim.get("min_separation_m"),
                   "near_misses": sim.get("near_misses"), "near_miss_m": near_m},
        "lockstep_step_timeouts": sim.get("lockstep_step_timeouts"),
    }
    lt_path = os.path.join(run, "loadtest.json")
    lt = json.load(open(lt_path)) if os.path.exists(lt_path) else None
    if lt:
        summary["loadtest"] = {k: lt.get(k) for k in ("accounting", "throughput", "real_time_factor", "wall_time_s",
                                                     "agent_processes", "fault_plan", "faults", "tasks",
                                                     "wall_limited", "interrupted", "store")}
        summary["loadtest"]["kinematic_bound"] = {k: v for k, v in (lt.get("kinematic_bound") or {}).items()
                                                  if k != "per_task"}
        if lt.get("saturated"):
            summary["loadtest"]["saturated"] = lt["saturated"]
        for k in ("fleet_bound", "robot_time", "stations"):
            if lt.get(k) is not None:
                summary["loadtest"][k] = lt[k]
    json.dump(summary, open(os.path.join(run, "summary.json"), "w"), indent=2)
    risk = risk_levels_over_time(run)
    viewer = embedded_viewer(run)

    state_rows = "".join(f'<tr><td>{html.escape(str(k))}</td><td class="r">{v}</td></tr>' for k, v in sorted(states.items())) \
        or '<tr><td colspan="2">(no tasks)</td></tr>'
    contacts = sim.get("contacts", {}) or {}
    near = sim.get("near_misses", {}) or {}
    sep = sim.get("min_separation_m", {}) or {}
    gap = lambda v: "—" if v is None else f"{v:.3f}"
    bad = lambda v: ' class="r bad"' if v else ' class="r"'
    safety_rows = "".join(
        f"<tr><td>{label}</td><td{bad(contacts.get(k))}>{contacts.get(k, '—')}</td>"
        f"<td class=\"r\">{near[k] if k in near else 'not counted'}</td><td class=\"r\">{gap(sep.get(k))}</td></tr>"
        for label, k in (("robot – robot", "robot_robot"), ("robot – human", "robot_human"), ("robot – shelf", "robot_shelf")))
    near_txt = f"closer than {near_m:g} m" if near_m is not None else "close"
    timeouts = sim.get("lockstep_step_timeouts")
    times = latency_table([("assignment latency", "submitted → first assigned", summary["assignment_latency_s"]),
                           ("execution time", "first assigned → done", summary["tasks"]["execution_time_s"]),
                           ("task time (end to end)", "submitted → done", end_to_end)])
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>Fleet run {html.escape(os.path.basename(os.path.abspath(run)))}</title>
<style>body{{font-family:sans-serif;margin:20px;color:#222;max-width:1400px}} table{{border-collapse:collapse;margin-bottom:8px}}
td,th{{border:1px solid #ccc;padding:3px 8px;font-size:14px}} th{{background:#f2f2f2;font-weight:600}} td.r{{text-align:right;font-variant-numeric:tabular-nums}}
td.bad{{color:#b00;font-weight:bold}} h2{{border-bottom:1px solid #ddd;padding-bottom:3px;margin-top:28px}} h3{{margin:14px 0 4px;font-size:15px}}
.grid{{display:flex;gap:28px;flex-wrap:wrap;align-items:flex-start}} .note{{color:#555;font-size:13px;max-width:520px}}
.nodata{{display:flex;align-items:center;justify-content:center;border:1px dashed #bbb;color:#777;font-size:13px}}
iframe{{border:1px solid #aaa;width:100%;max-width:1200px;height:790px}} nav a{{margin-right:12px}}</style></head><body>
<h1>Fleet run: {html.escape(str(summary['scenario']))}</h1>
<p>{summary['robots']} robots, {summary['humans']} humans, {sim_s:.0f} s of simulated time.
<b>{done}</b> of {summary['tasks']['submitted']} tasks done ({summary['tasks']['per_hour']:.0f} per simulated hour);
<b class="{'bad' if sum(v or 0 for k, v in contacts.items() if k != 'steps_with_contact') else ''}">{contacts.get('robot_robot', '—')} robot–robot and {contacts.get('robot_human', '—')} robot–human contacts</b>.</p>
<nav><a href="#throughput">Throughput &amp; latency</a><a href="#safety">Safety</a><a href="#risk">Risk map</a><a href="#traffic">Traffic</a><a href="#localization">Localization</a>{'<a href="#loadtest">Load test</a>' if lt else ''}<a href="#replay">Replay</a><a href="#raw">Raw summary</a></nav>
<h2 id="throughput">Throughput and latency</h2>
<p class="note" style="max-width:900px">All times are seconds of simulated time, from the fleet manager's task database (every task it stored).
Percentiles are nearest-rank; a task restarted before the manager had a clock gives no samples.</p>
<div class="grid">
<div><h3>Tasks by state</h3><table><tr><th>state</th><th>tasks</th></tr>{state_rows}</table></div>
<div><h3>Task times and latencies (s)</h3>{times}</div>
</div>
<div class="grid">
<div><h3>Tasks done over time</h3>{svg_line(cumulative if done else [], xlabel='simulated time (s)', ylabel='tasks done (cumulative)', why='no task reached done')}</div>
<div><h3>Execution time distribution (first assigned → done)</h3>{svg_hist(executions, xlabel='execution time (s)', why='no task reached done', color='#9467bd')}</div>
<div><h3>Assignment latency distribution (submitted → first assigned)</h3>{svg_hist(assign_lat, xlabel='assignment latency (s)', why='no task was assigned', color='#1f77b4')}</div>
<div><h3>End-to-end latency distribution (task time: submitted → done)</h3>{svg_hist(durations, xlabel='end-to-end latency (s)', why='no task reached done', color='#2ca02c')}</div>
</div>
<h2 id="safety">Safety</h2>
<div class="grid"><div><table><tr><th>bodies</th><th>contacts</th><th>near misses ({html.escape(near_txt)})</th><th>minimum surface gap (m)</th></tr>{safety_rows}</table>
<p class="note">Contacts and near misses count episodes (a pair coming into touch or into near-miss range once, however
long it stays). A negative gap is an overlap; a gap of "—": no such pair ever came within 2 m (separations are tracked only closer than that).
{contacts.get('steps_with_contact', 0)} simulation steps had a contact{f"; {timeouts} lockstep step timeouts" if timeouts else ""}.</p></div></div>
<h2 id="risk">Risk map iso-levels over time</h2>
<div class="grid"><div>{svg_lines(risk, w=640, h=260, xlabel='simulated time (s)', ylabel='area (m²)', legend_title='collision p', why='no risk map in the replay (was the risk map service running?)')}</div>
<p class="note">Area of the warehouse floor whose collision probability exceeds each iso-level's lower bound, for each risk map
the simulator recorded. Level l of K holds p in ((l−1)/K, l/K].</p></div>
{localization_html(run, lt)}
{traffic_html(run)}
{loadtest_html(lt, saturated_html(lt.get("saturated") if lt else None, waiting_series(db) if lt and lt.get("clock") != "wall" else [], done_at, sim.get("sim_time_s", 0)))}
<h2 id="replay">Replay</h2><p>Robots (orange) with task labels, humans (blue), contacts highlighted, risk-map iso-levels shaded;
in reserved traffic the roadmap, its queue places and closed nodes, and each robot's released base (solid) and horizon (dashed).
The viewer is embedded in this page; <a href="viewer.html">open it on its own</a> (viewer.html, next to this page in the run folder).</p>
{viewer}
<h2 id="raw">Raw summary</h2><details><summary>summary.json</summary><pre>{html.escape(json.dumps(summary, indent=2))}</pre></details>
</body></html>"""
    open(os.path.join(run, "index.html"), "w").write(page)
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main(sys.argv[1])
