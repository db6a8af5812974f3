#!/usr/bin/env python3
"""Writes the fleet run report (index.html + summary.json) from what a demo or load-test run left
in its folder: the simulator's summary and replay viewer, the fleet manager's task database and
metrics. Usage: scripts/report.py RUN_DIR"""
import gzip
import html
import json
import math
import os
import sqlite3
import sys

COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"]


def svg_lines(series, w=520, h=220, xlabel="", ylabel=""):
    """Several named lines [(name, [(x, y)...])] on shared axes, with a legend."""
    series = [(n, pts) for n, pts in series if pts]
    if not series:
        return "<p>(no data)</p>"
    xs = [x for _, pts in series for x, _ in pts]
    x0, x1 = min(xs), max(xs)
    y1 = max(y for _, pts in series for _, y in pts) or 1
    sx = lambda x: 50 + (x - x0) / ((x1 - x0) or 1) * (w - 150)
    sy = lambda y: h - 35 - y / y1 * (h - 55)
    paths, legend = [], []
    for i, (name, pts) in enumerate(series):
        c = COLORS[i % len(COLORS)]
        d = " ".join(f"{'M' if k == 0 else 'L'}{sx(x):.1f},{sy(y):.1f}" for k, (x, y) in enumerate(pts))
        paths.append(f'<path d="{d}" fill="none" stroke="{c}" stroke-width="1.5"/>')
        legend.append(f'<text x="{w-92}" y="{24+i*13}" fill="{c}">{html.escape(name)}</text>')
    return (f'<svg width="{w}" height="{h}" xmlns="http://www.w3.org/2000/svg" font-size="11">'
            f'<line x1="50" y1="{h-35}" x2="{w-100}" y2="{h-35}" stroke="#444"/>'
            f'<line x1="50" y1="20" x2="50" y2="{h-35}" stroke="#444"/>{"".join(paths)}{"".join(legend)}'
            f'<text x="{(w-100)/2}" y="{h-8}" text-anchor="middle">{html.escape(xlabel)}</text>'
            f'<text x="12" y="{h/2}" transform="rotate(-90 12 {h/2})" text-anchor="middle">{html.escape(ylabel)}</text>'
            f'<text x="46" y="24" text-anchor="end">{y1:.3g}</text><text x="46" y="{h-35}" text-anchor="end">0</text>'
            f'<text x="50" y="{h-22}">{x0:g}</text><text x="{w-100}" y="{h-22}" text-anchor="end">{x1:g}</text></svg>')


def risk_levels_over_time(run):
    """Area (m²) of the risk map at or above each iso-level, per recorded map in the replay."""
    path = os.path.join(run, "replay.jsonl.gz")
    if not os.path.exists(path):
        return []
    levels = {}
    with gzip.open(path, "rt") as f:
        for line in f:
            if '"risk"' not in line:
                continue
            d = json.loads(line)
            r = d.get("risk")
            if not r or "runs" not in r:
                continue
            cell = r.get("resolution", 0.1) ** 2
            counts = [0] * (r.get("levels", 10) + 1)
            for level, n in r["runs"]:
                if 0 <= level < len(counts):
                    counts[level] += n
            for l in range(1, len(counts)):
                levels.setdefault(l, []).append((d.get("t", 0.0), sum(counts[l:]) * cell))
    k = max(levels) if levels else 0
    return [(f"p >= {l / k:.1f}", pts) for l, pts in sorted(levels.items()) if l in (1, 2, 3, 5, 7, 9, k)]


def svg_line(points, w=520, h=220, xlabel="", ylabel=""):
    if not points:
        return "<p>(no data)</p>"
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    x0, x1 = min(xs), max(xs) or 1
    y1 = max(ys) or 1
    sx = lambda x: 50 + (x - x0) / ((x1 - x0) or 1) * (w - 70)
    sy = lambda y: h - 35 - y / y1 * (h - 55)
    path = " ".join(f"{'M' if i == 0 else 'L'}{sx(x):.1f},{sy(y):.1f}" for i, (x, y) in enumerate(points))
    return (f'<svg width="{w}" height="{h}" xmlns="http://www.w3.org/2000/svg" font-size="11">'
            f'<line x1="50" y1="{h-35}" x2="{w-20}" y2="{h-35}" stroke="#444"/>'
            f'<line x1="50" y1="20" x2="50" y2="{h-35}" stroke="#444"/>'
            f'<path d="{path}" fill="none" stroke="#1f77b4" stroke-width="2"/>'
            f'<text x="{w/2}" y="{h-8}" text-anchor="middle">{html.escape(xlabel)}</text>'
            f'<text x="12" y="{h/2}" transform="rotate(-90 12 {h/2})" text-anchor="middle">{html.escape(ylabel)}</text>'
            f'<text x="46" y="24" text-anchor="end">{y1:g}</text><text x="46" y="{h-35}" text-anchor="end">0</text>'
            f'<text x="50" y="{h-22}">{x0:g}</text><text x="{w-20}" y="{h-22}" text-anchor="end">{x1:g}</text></svg>')


def svg_hist(values, bins=12, w=520, h=220, xlabel=""):
    if not values:
        return "<p>(no data)</p>"
    lo, hi = min(values), max(values)
    width = (hi - lo) / bins or 1
    counts = [0] * bins
    for v in values:
        counts[min(bins - 1, int((v - lo) / width))] += 1
    top = max(counts)
    bw = (w - 70) / bins
    bars = "".join(
        f'<rect x="{50 + i*bw:.1f}" y="{h-35-(c/top)*(h-55):.1f}" width="{bw-2:.1f}" height="{(c/top)*(h-55):.1f}" fill="#2ca02c"/>'
        for i, c in enumerate(counts))
    return (f'<svg width="{w}" height="{h}" xmlns="http://www.w3.org/2000/svg" font-size="11">{bars}'
            f'<line x1="50" y1="{h-35}" x2="{w-20}" y2="{h-35}" stroke="#444"/>'
            f'<text x="{w/2}" y="{h-8}" text-anchor="middle">{html.escape(xlabel)}</text>'
            f'<text x="50" y="{h-22}">{lo:.0f}</text><text x="{w-20}" y="{h-22}" text-anchor="end">{hi:.0f}</text>'
            f'<text x="46" y="24" text-anchor="end">{top}</text></svg>')


def pct(values, q):
    if not values:
        return None
    v = sorted(values)  # nearest rank, as fleetctl's task ledger
    return v[min(len(v), max(1, math.ceil(q * len(v)))) - 1]


def loadtest_html(lt):
    if not lt:
        return ""
    a = lt.get("accounting", {})
    bad = (a.get("lost", 0) or 0) + (a.get("duplicated", 0) or 0)
    verdict = (f'<p style="font-size:1.3em;color:{"#b00" if bad else "#070"}"><b>{a.get("lost")} lost, '
               f'{a.get("duplicated")} duplicated</b> of {a.get("acknowledged")} acknowledged tasks</p>')
    rows = lambda d: "".join(f"<tr><td>{html.escape(str(k))}</td><td>{html.escape(json.dumps(v))}</td></tr>" for k, v in d.items())
    acc = {k: a.get(k) for k in ("acknowledged", "done", "failed", "cancelled", "still_tracked", "lost",
                                 "duplicated", "known_not_acknowledged", "unstamped")}
    faults = "".join(f"<tr><td>{e.get('sim_s', 0):.1f}</td><td>{html.escape(e.get('event', ''))}</td></tr>"
                     for e in lt.get("faults", []))
    progress = [(p["wall_s"], p["sim_s"]) for p in lt.get("progress", [])]
    # The robot agent processes: the control rate they achieved and how their robots dealt with
    # each other (agent-K_metrics.json, collected by fleetctl loadtest).
    agent_rows = "".join(
        f"<tr><td>{html.escape(str(m.get('id', '?')))}</td><td>{m.get('robots', 0)}</td>"
        f"<td>{m.get('achieved_hz', 0):.2f} / {m.get('configured_hz', 0):.0f}</td><td>{m.get('overruns', 0)}</td>"
        f"<td>{m.get('cycle_ms', {}).get('p50', 0):.2f} / {m.get('cycle_ms', {}).get('p99', 0):.2f}</td>"
        f"<td>{m.get('conduct', {}).get('standoffs', 0)} / {m.get('conduct', {}).get('wait_cycles', 0)} / "
        f"{m.get('conduct', {}).get('backoffs', 0)} / {m.get('conduct', {}).get('returns', 0)} / "
        f"{m.get('conduct', {}).get('detours', 0)}</td></tr>"
        for m in lt.get("agents", []))
    agents = (f"<h3>Robot agents ({html.escape(str(lt.get('clock', 'lockstep')))} clock)</h3><table>"
              "<tr><td>process</td><td>robots</td><td>cycles/s (achieved / configured)</td><td>overruns</td>"
              "<td>cycle ms p50 / p99</td><td>standoffs / wait cycles / back-offs / returns / detours</td></tr>"
              f"{agent_rows}</table>") if agent_rows else ""
    return f"""<h2>Load test</h2>{verdict}
<p>{lt.get('robots')} robots in {lt.get('agent_processes')} agent process(es), {lt.get('humans')} humans,
{lt.get('sim_time_s', 0):.0f} s simulated in {lt.get('wall_time_s', 0):.0f} s wall
(<b>{lt.get('real_time_factor', 0):.2f}×</b> real time){' — stopped by the wall-time limit' if lt.get('wall_limited') else ''}.
Arrival rate {lt.get('rate_per_min', 0):g} tasks per simulated minute. Fault plan: {html.escape(', '.join(lt.get('fault_plan', [])) or 'none')}.</p>
<div class="grid"><div><h3>Acknowledged tasks</h3><table>{rows(acc)}</table>
<h3>Throughput</h3><table>{rows(lt.get('throughput', {}))}</table></div>
<div><h3>Latency (s, simulated)</h3><table><tr><td></td><td>p50</td><td>p90</td><td>p99</td><td>max</td><td>n</td></tr>
{''.join(f"<tr><td>{n}</td>" + ''.join(f"<td>{a.get(k, {}).get(q, 0):.2f}</td>" for q in ('p50', 'p90', 'p99', 'max')) + f"<td>{a.get(k, {}).get('count', 0)}</td></tr>" for n, k in (('assignment', 'assignment_latency_s'), ('end to end', 'end_to_end_latency_s')))}</table>
<h3>Faults injected</h3><table><tr><td>sim s</td><td>event</td></tr>{faults}</table></div>
<div><h3>Simulated vs wall time</h3>{svg_line(progress, xlabel='wall time (s)', ylabel='simulated time (s)')}</div></div>
{agents}"""


def main(run):
    sim = json.load(open(os.path.join(run, "sim_summary.json")))
    metrics_path = os.path.join(run, "manager_metrics_final.json")
    manager = json.load(open(metrics_path)) if os.path.exists(metrics_path) else {}
    db = sqlite3.connect(os.path.join(run, "fleet.db"))
    states = dict(db.execute("select state, count(*) from tasks group by state").fetchall())
    created = {}
    assigned = set()
    unstamped = set()
    latest = 0
    done_at = []
    durations = []
    assign_lat = []
    for task, to, stamp in db.execute("select task_id, to_state, stamp_ns from transitions order by seq"):
        if task not in created:
            created[task] = stamp
            # A restarted manager stamps tasks it stores before its first Clock with 0 (see
            # fleetctl's task ledger): no latency samples from those.
            if stamp + 1e9 < latest:
                unstamped.add(task)
        latest = max(latest, stamp)
        if to == "done":
            done_at.append(stamp / 1e9)
            if task not in unstamped:
                durations.append((stamp - created[task]) / 1e9)
        if to == "assigned" and task not in assigned:
            assigned.add(task)
            if task not in unstamped:
                assign_lat.append((stamp - created[task]) / 1e9)
    sim_s = sim.get("sim_time_s", 0) or 1
    done = len(done_at)
    cumulative = [(0.0, 0)]
    for i, t in enumerate(sorted(done_at)):  # a step up at each completion
        cumulative += [(t, i), (t, i + 1)]
    cumulative.append((sim_s, done))
    summary = {
        "scenario": sim.get("scenario"),
        "sim_time_s": sim_s,
        "robots": sim.get("robots"),
        "humans": sim.get("humans"),
        "tasks": {"submitted": sum(states.values()), "by_state": states, "done": done,
                  "per_hour": done * 3600.0 / sim_s,
                  "time_s": {"p50": pct(durations, 0.5), "p90": pct(durations, 0.9), "max": pct(durations, 1.0)}},
        "assignment_latency_s": {"p50": pct(assign_lat, 0.5), "p90": pct(assign_lat, 0.9),
                                 "p99": pct(assign_lat, 0.99), "max": pct(assign_lat, 1.0)},
        "manager_assignment_latency_ms": manager.get("assign_latency_ms"),
        "requeued": manager.get("requeued"),
        "safety": {"contacts": sim.get("contacts"), "min_separation_m": sim.get("min_separation_m"),
                   "near_misses": sim.get("near_misses")},
        "lockstep_step_timeouts": sim.get("lockstep_step_timeouts"),
    }
    lt_path = os.path.join(run, "loadtest.json")
    lt = json.load(open(lt_path)) if os.path.exists(lt_path) else None
    if lt:
        summary["loadtest"] = {k: lt.get(k) for k in ("accounting", "throughput", "real_time_factor", "wall_time_s",
                                                     "agent_processes", "fault_plan", "faults", "tasks",
                                                     "wall_limited", "interrupted")}
    json.dump(summary, open(os.path.join(run, "summary.json"), "w"), indent=2)
    risk = risk_levels_over_time(run)

    rows = lambda d: "".join(f"<tr><td>{html.escape(str(k))}</td><td>{html.escape(json.dumps(v))}</td></tr>" for k, v in d.items())
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>Fleet run {html.escape(os.path.basename(run))}</title>
<style>body{{font-family:sans-serif;margin:20px;color:#222}} table{{border-collapse:collapse}} td{{border:1px solid #ccc;padding:3px 8px}}
.grid{{display:flex;gap:24px;flex-wrap:wrap}} iframe{{border:1px solid #aaa;width:100%;height:820px}}</style></head><body>
<h1>Fleet run: {html.escape(str(summary['scenario']))}</h1>
<p>{summary['robots']} robots, {summary['humans']} humans, {sim_s:.0f} s of simulated time.
<b>{done}</b> of {summary['tasks']['submitted']} tasks done ({summary['tasks']['per_hour']:.0f} per hour).</p>
<div class="grid">
<div><h2>Tasks</h2><table>{rows(states)}</table>
<h3>Task time (s)</h3><table>{rows(summary['tasks']['time_s'])}</table>
<h3>Assignment latency (s of simulated time, stored → first assigned)</h3><table>{rows(summary['assignment_latency_s'])}</table></div>
<div><h2>Safety</h2><table>{rows(sim.get('contacts', {}))}</table><h3>Minimum separations (m)</h3><table>{rows(sim.get('min_separation_m', {}))}</table>
<h3>Near misses</h3><table>{rows(sim.get('near_misses', {}))}</table></div>
<div><h2>Tasks done over time</h2>{svg_line(cumulative, xlabel='simulated time (s)', ylabel='tasks done')}
<h2>Task time distribution (end to end)</h2>{svg_hist(durations, xlabel='seconds from submission to done')}
<h2>Assignment latency distribution</h2>{svg_hist(assign_lat, xlabel='seconds from submission to first assignment')}</div>
<div><h2>Risk map iso-levels over time</h2>{svg_lines(risk, xlabel='simulated time (s)', ylabel='area at or above the level (m²)')}</div>
</div>
{loadtest_html(lt)}
<h2>Replay</h2><p>Robots (orange) with task labels, humans (blue), contacts highlighted, risk-map iso-levels shaded.
<a href="viewer.html">Open the viewer on its own</a>.</p>
<iframe src="viewer.html"></iframe>
<h2>Raw summary</h2><pre>{html.escape(json.dumps(summary, indent=2))}</pre>
</body></html>"""
    open(os.path.join(run, "index.html"), "w").write(page)
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main(sys.argv[1])
