#!/usr/bin/env python3
"""Position and heading error over time of load-test runs side by side (their localization.json,
written by fleet-sim --localization), as two SVG files for docs/benchmarks.md.
Usage: scripts/localization-figure.py OUT_PREFIX LABEL=RUN_DIR [LABEL=RUN_DIR ...]
writes OUT_PREFIX-position.svg and OUT_PREFIX-heading.svg and prints each run's figures."""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report  # noqa: E402  (the report's plotting)


def main(prefix, specs):
    runs, hidden = [], []
    for spec in specs:
        label, run = spec.split("=", 1)
        loc = json.load(open(os.path.join(run, "localization.json")))
        runs.append((label, loc["series"]))
        hidden = hidden or sorted(tuple(h) for h in loc.get("hidden", []))
        for key in ("overall", "hidden_stretches", "visible_stretches"):
            s = loc[key]
            print(f"{label:>14} {key:<18} n={s['samples']:>7} pos rmse {s['pos_rmse']*100:6.2f} cm p95 {s['pos_p95']*100:6.2f} "
                  f"max {s['pos_max']*100:6.2f} | heading rmse {math.degrees(s['head_rmse']):5.2f}° max {math.degrees(s['head_max']):5.2f}°")
        last = [p for p in loc["series"] if p["t"] >= loc["series"][-1]["t"] - 60]
        print(f"{label:>14} last 60 s: mean pos {sum(p['pos_mean'] for p in last)/len(last)*100:.2f} cm, "
              f"worst robot {max(p['pos_max'] for p in last)*100:.2f} cm")
    with open(prefix + "-position.svg", "w") as f:
        f.write(report.svg_error(runs, hidden, "pos", 100, w=760, h=300, ylabel="position error (cm)"))
    with open(prefix + "-heading.svg", "w") as f:
        f.write(report.svg_error(runs, hidden, "head", 180 / math.pi, w=760, h=300, ylabel="|heading error| (°)"))


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
