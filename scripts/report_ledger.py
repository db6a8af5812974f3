"""The fleet bound, the robot-time ledger and the station ledger of a load-test run (loadtest.json's
fleet_bound, robot_time and stations blocks), for scripts/report.py."""
import html

CATEGORY_COLOURS = {"no_task": "#c7c7c7", "driving": "#2ca02c", "turning_docking": "#98df8a", "dwelling": "#1f77b4",
                    "waiting_on_robot": "#ff7f0e", "held_by_person": "#d62728", "held_by_safety": "#9467bd",
                    "charging": "#17becf", "faulted": "#000000"}


def fleet_bound_html(b):
    if not b:
        return ""
    if "error" in b:
        return f"<h3>Against the fleet bound</h3><p>not computed: {html.escape(str(b['error']))}</p>"
    rows = [("the fleet", f"{b.get('fleet_rate_per_h', 0):.1f} tasks/h = <b>{100 * b.get('fraction_of_bound', 0):.0f} %</b> "
                          f"of the fleet bound ({html.escape(str(b.get('binds')))} bind)"),
            ("fleet bound = min(robots, stations)", f"{b.get('bound_per_h', 0):.1f} tasks/h"),
            ("robot bound", f"{b.get('robots')} × a lone robot's {b.get('lone_rate_per_h', 0):.1f}/h = "
                            f"{b.get('robot_bound_per_h', 0):.1f} tasks/h"),
            ("the lone robot's chain through the list", f"{b.get('lone_chain_m', 0):.0f} m, {b.get('lone_chain_s', 0):.0f} s "
                                                        f"for {b.get('tasks')} tasks"),
            ("station bound", f"{b.get('station_bound_per_h', 0):.1f} tasks/h (busiest {html.escape(str(b.get('binding_station')))})")]
    table = "".join(f"<tr><td>{html.escape(k)}</td><td class=\"r\">{v}</td></tr>" for k, v in rows)
    st = "".join(f"<tr><td>{html.escape(s['name'])}</td><td class=\"r\">{s['visits']}</td><td class=\"r\">{s['share']:.3f}</td>"
                 f"<td class=\"r\">{s['cycle_s']:.1f}</td><td class=\"r\">{s['bound_per_h']:.0f}</td></tr>"
                 for s in b.get("stations", [])[:8])
    return f"""<h3>Against the fleet bound</h3><div class="grid"><div><table>{table}</table>
<p class="note">{html.escape(str(b.get('definition', '')))}</p></div>
<div><table><tr><th>station</th><th>visits</th><th>per task f<sub>s</sub></th><th>least cycle c<sub>s</sub> [s]</th>
<th>bound [tasks/h]</th></tr>{st}</table></div></div>"""


def robot_time_html(rt, w=640, bar=14):
    """A stacked bar per robot of its time in the nine categories, and the fleet's shares."""
    if not rt:
        return ""
    if "error" in rt:
        return f"<h3>Robot time</h3><p>not computed: {html.escape(str(rt['error']))}</p>"
    cats = rt.get("categories", [])
    per = rt.get("per_robot", {})
    left = 70
    h = 30 + bar * len(per) + 30
    out = [f'<svg width="{w}" height="{h}" font-size="10">']
    for i, (robot, d) in enumerate(per.items()):
        y = 20 + i * bar
        out.append(f'<text x="0" y="{y + bar - 4}">{html.escape(robot)}</text>')
        x = left
        for c in cats:
            width = (w - left - 10) * d.get("share", {}).get(c, 0)
            if width > 0:
                out.append(f'<rect x="{x:.1f}" y="{y}" width="{width:.1f}" height="{bar - 2}" fill="{CATEGORY_COLOURS.get(c, "#888")}">'
                           f'<title>{html.escape(robot)}: {c.replace("_", " ")} {100 * d["share"][c]:.1f} %</title></rect>')
                x += width
    y = 30 + bar * len(per)
    x = 0
    for c in cats:
        out.append(f'<rect x="{x}" y="{y}" width="10" height="10" fill="{CATEGORY_COLOURS.get(c, "#888")}"/>'
                   f'<text x="{x + 13}" y="{y + 9}">{c.replace("_", " ")}</text>')
        x += 13 + 6 * len(c) + 8
    out.append("</svg>")
    fleet = " · ".join(f"{c.replace('_', ' ')} <b>{100 * rt.get('fleet', {}).get(c, 0):.0f} %</b>" for c in cats)
    return (f"<h3>Robot time</h3><p>Fleet: {fleet}.</p>{''.join(out)}"
            f"<p class=\"note\">{html.escape(str(rt.get('note', '')))} (source here: {html.escape(str(rt.get('source')))}).</p>")


def docking_cell(s):
    if "dockings" not in s:
        return "<td class=\"r\">–</td>"
    return (f"<td class=\"r\">{s['docking_p50_s']:.1f} / {s['docking_p90_s']:.1f} / {s['docking_max_s']:.1f} "
            f"(model {s['dock_model_s']:.2f}; {s['dockings'] - s['dockings_over_model']} of {s['dockings']} within +2 s)</td>")


def queue_sparkline(series, every_s, top, w=160, h=22):
    """The station's queue over the run as a step line (one sample every `every_s` s), all rows on
    one scale (`top` robots at the top), so stations compare at a glance."""
    if not series or every_s <= 0:
        return "–"
    top = max(1, top)
    n = len(series)
    pts = []
    for i, q in enumerate(series):
        x0, x1 = w * i / n, w * (i + 1) / n
        y = h - 1 - (h - 2) * min(q, top) / top
        pts.append(f"{x0:.1f},{y:.1f} {x1:.1f},{y:.1f}")
    return (f'<svg class="queue" width="{w}" height="{h}" role="img" aria-label="queue over the run">'
            f'<rect width="{w}" height="{h}" fill="#f4f4f4"/><polyline fill="none" stroke="#ff7f0e" stroke-width="1.5" '
            f'points="{" ".join(pts)}"><title>{n} samples every {every_s:g} s, max {max(series)}</title></polyline></svg>')


def stations_html(stations):
    if not stations:
        return ""
    top = max((max(s.get("queue_series") or [0]) for s in stations), default=0)
    rows = "".join(
        f"<tr><td>{html.escape(s['name'])}</td><td class=\"r\">{s['visits']}</td><td class=\"r\">{100 * s['utilisation']:.0f} %</td>"
        f"<td class=\"r\">{s['queue_mean']:.2f} / {s['queue_max']}</td>"
        f"<td>{queue_sparkline(s.get('queue_series'), s.get('queue_every_s', 0), top)}</td>"
        f"<td class=\"r\">{s['cycle_p50_s']:.1f} / {s['cycle_p90_s']:.1f} ({s['cycles']})</td>"
        f"<td class=\"r\">{s['occupancy_p50_s']:.1f} / {s['occupancy_p90_s']:.1f}</td>{docking_cell(s)}</tr>" for s in stations)
    return f"""<h3>Stations</h3><table><tr><th>station</th><th>visits</th><th>utilisation (docked ÷ run)</th>
<th>queue mean / max</th><th>queue over the run (0–{max(1, top)})</th><th>dock cycle p50 / p90 [s] (cycles)</th><th>occupancy per visit p50 / p90 [s]</th>
<th>docking p50 / p90 / max [s]</th></tr>{rows}</table>
<p class="note">Docked: the robot's centre within 0.25 m of the station's pose. Queue: robots whose current goal is the
station and are not docked there. Dock cycle: one robot's dock arrival to the next's, counted when the next stood in the
station's line (its queue places and approach) as the first left (the fleet bound's c<sub>s</sub> is its least value with
ideal motion). Docking: from the robot's last step within 0.25 m of the station's entry (approach, or queue head) to the
dock, against that span at cruise.</p>"""
