#!/usr/bin/env python3
"""Writes the fleet run report (index.html + summary.json) from what a demo or load-test run left
in its folder: the simulator's summary and replay viewer, the fleet manager's task database and
metrics. Usage: scripts/report.py RUN_DIR"""
import html
import json
import os
import sqlite3
import sys


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
    v = sorted(values)
    return v[min(len(v) - 1, int(q * (len(v) - 1)))]


def main(run):
    sim = json.load(open(os.path.join(run, "sim_summary.json")))
    metrics_path = os.path.join(run, "manager_metrics_final.json")
    manager = json.load(open(metrics_path)) if os.path.exists(metrics_path) else {}
    db = sqlite3.connect(os.path.join(run, "fleet.db"))
    states = dict(db.execute("select state, count(*) from tasks group by state").fetchall())
    created = {}
    done_at = []
    durations = []
    for task, to, stamp in db.execute("select task_id, to_state, stamp_ns from transitions order by seq"):
        if task not in created:
            created[task] = stamp
        if to == "done":
            done_at.append(stamp / 1e9)
            durations.append((stamp - created[task]) / 1e9)
    sim_s = sim.get("sim_time_s", 0) or 1
    done = len(done_at)
    cumulative = [(0.0, 0)] + [(t, i + 1) for i, t in enumerate(sorted(done_at))] + [(sim_s, done)]
    summary = {
        "scenario": sim.get("scenario"),
        "sim_time_s": sim_s,
        "robots": sim.get("robots"),
        "humans": sim.get("humans"),
        "tasks": {"submitted": sum(states.values()), "by_state": states, "done": done,
                  "per_hour": done * 3600.0 / sim_s,
                  "time_s": {"p50": pct(durations, 0.5), "p90": pct(durations, 0.9), "max": pct(durations, 1.0)}},
        "assignment_latency_ms": manager.get("assign_latency_ms"),
        "requeued": manager.get("requeued"),
        "safety": {"contacts": sim.get("contacts"), "min_separation_m": sim.get("min_separation_m"),
                   "near_misses": sim.get("near_misses")},
        "lockstep_step_timeouts": sim.get("lockstep_step_timeouts"),
    }
    json.dump(summary, open(os.path.join(run, "summary.json"), "w"), indent=2)

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
<h3>Assignment latency (ms, queued → assigned)</h3><table>{rows(summary['assignment_latency_ms'] or {})}</table></div>
<div><h2>Safety</h2><table>{rows(sim.get('contacts', {}))}</table><h3>Minimum separations (m)</h3><table>{rows(sim.get('min_separation_m', {}))}</table>
<h3>Near misses</h3><table>{rows(sim.get('near_misses', {}))}</table></div>
<div><h2>Tasks done over time</h2>{svg_line(cumulative, xlabel='simulated time (s)', ylabel='tasks done')}
<h2>Task time distribution</h2>{svg_hist(durations, xlabel='seconds from submission to done')}</div>
</div>
<h2>Replay</h2><p>Robots (orange) with task labels, humans (blue), contacts highlighted, risk-map iso-levels shaded.
<a href="viewer.html">Open the viewer on its own</a>.</p>
<iframe src="viewer.html"></iframe>
<h2>Raw summary</h2><pre>{html.escape(json.dumps(summary, indent=2))}</pre>
</body></html>"""
    open(os.path.join(run, "index.html"), "w").write(page)
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main(sys.argv[1])
